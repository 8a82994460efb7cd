#include "endotower/media/media_library.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>

namespace endotower::media {

namespace {

std::string lower_extension(const std::filesystem::path& p) {
    std::string e = p.extension().string();
    std::transform(e.begin(), e.end(), e.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e;
}

bool has_dicom_mark(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    char head[132] = {};
    return in.read(head, sizeof head) && std::string_view(head + 128, 4) == "DICM";
}

}  // namespace

bool MediaLibrary::load(const std::string& folder, std::string& error) {
    namespace fs = std::filesystem;
    images_.clear();
    patient_.reset();
    problems_.clear();
    std::error_code ec;
    std::vector<fs::path> files;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
        if (it->is_regular_file(ec) && it->path().filename().string().front() != '.')
            files.push_back(it->path());
    if (ec) {
        error = folder + ": cannot list the media folder (" + ec.message() + ")";
        return false;
    }
    std::sort(files.begin(), files.end(),
              [](const fs::path& a, const fs::path& b) { return a.filename() < b.filename(); });
    for (const fs::path& f : files) {
        if (f.filename() == kPatientFile) continue;
        const std::string ext = lower_extension(f);
        const bool image = ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".dcm" ||
                           has_dicom_mark(f);
        if (!image) continue;
        MediaImage img;
        std::string why;
        if (load_media_image(f.string(), img, why)) images_.push_back(std::move(img));
        else problems_.push_back(why);
    }
    PatientRecord record;
    std::string why;
    if (load_patient_record((fs::path(folder) / kPatientFile).string(), record, why))
        patient_ = std::move(record);
    else
        problems_.push_back(why);
    return true;
}

}  // namespace endotower::media
