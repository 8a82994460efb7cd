// MediaLibrary: the media folder named in the board file, loaded off the per-frame
// path (it reads and decodes every file).
//
// load(folder): the images (*.png, *.jpg, *.jpeg, *.dcm, and any other file with the
// DICOM mark) in file-name order, and the patient record `patient.txt`
// (patient_record.hpp). A file that is missing, unreadable or corrupt is skipped and
// listed in problems() as "PATH: what is wrong", which the interface shows in the
// overlay and the log; the other files still load. load() itself fails only when
// the folder cannot be listed.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "endotower/media/media_image.hpp"
#include "endotower/media/patient_record.hpp"

namespace endotower::media {

class MediaLibrary {
public:
    static constexpr const char* kPatientFile = "patient.txt";

    bool load(const std::string& folder, std::string& error);

    const std::vector<MediaImage>& images() const { return images_; }
    const std::optional<PatientRecord>& patient() const { return patient_; }
    const std::vector<std::string>& problems() const { return problems_; }

private:
    std::vector<MediaImage> images_;
    std::optional<PatientRecord> patient_;
    std::vector<std::string> problems_;
};

}  // namespace endotower::media
