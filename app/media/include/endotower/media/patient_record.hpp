// PatientRecord: the patient data the surgeon-computer interface shows next to the
// tool tip (fig. 4.35), read from a small text file of "key: value" lines:
//
//   # comments and blank lines are ignored
//   name: Anna Müller          (required, UTF-8)
//   id: 0042-77                (required)
//   birth_date: 1971-04-02     (optional, YYYY-MM-DD)
//   procedure: Cholecystectomy (optional)
//   notes: allergic to latex   (optional; repeated lines are joined by newlines)
//
// Errors: false, and `error` is "FILE:LINE: what is wrong" (an unknown or repeated
// key, a line without ':', a bad date, a value over 200 bytes) or "FILE: missing
// name/id". Never throws.
#pragma once

#include <string>
#include <string_view>

namespace endotower::media {

struct PatientRecord {
    std::string name, id, birth_date, procedure, notes;
};

bool parse_patient_record(std::string_view text, const std::string& file, PatientRecord& out,
                          std::string& error);

// Reads and parses `path`; a missing or unreadable file is an error naming it.
bool load_patient_record(const std::string& path, PatientRecord& out, std::string& error);

}  // namespace endotower::media
