#include "endotower/media/patient_record.hpp"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace endotower::media {

namespace {

constexpr std::size_t kMaxValue = 200;

std::string_view trim(std::string_view s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return s;
}

bool valid_date(std::string_view d) {
    if (d.size() != 10 || d[4] != '-' || d[7] != '-') return false;
    for (std::size_t i : {0, 1, 2, 3, 5, 6, 8, 9})
        if (!std::isdigit(static_cast<unsigned char>(d[i]))) return false;
    const int month = (d[5] - '0') * 10 + (d[6] - '0'), day = (d[8] - '0') * 10 + (d[9] - '0');
    return month >= 1 && month <= 12 && day >= 1 && day <= 31;
}

}  // namespace

bool parse_patient_record(std::string_view text, const std::string& file, PatientRecord& out,
                          std::string& error) {
    out = PatientRecord{};
    bool seen[4] = {false, false, false, false};  // name, id, birth_date, procedure
    int line_no = 0;
    while (!text.empty()) {
        ++line_no;
        const std::size_t nl = text.find('\n');
        std::string_view line = text.substr(0, nl);
        text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
        line = trim(line);
        if (line.empty() || line.front() == '#') continue;
        const std::string where = file + ":" + std::to_string(line_no) + ": ";
        const std::size_t colon = line.find(':');
        if (colon == std::string_view::npos) {
            error = where + "expected 'key: value'";
            return false;
        }
        const std::string_view key = trim(line.substr(0, colon));
        const std::string_view value = trim(line.substr(colon + 1));
        if (value.size() > kMaxValue) {
            error = where + "value of '" + std::string(key) + "' longer than " + std::to_string(kMaxValue) + " bytes";
            return false;
        }
        if (key == "notes") {
            if (!out.notes.empty()) out.notes += '\n';
            out.notes += value;
            continue;
        }
        static constexpr const char* kKeys[4] = {"name", "id", "birth_date", "procedure"};
        std::string* fields[4] = {&out.name, &out.id, &out.birth_date, &out.procedure};
        int k = 0;
        while (k < 4 && key != kKeys[k]) ++k;
        if (k == 4) {
            error = where + "unknown key '" + std::string(key) +
                    "' (name, id, birth_date, procedure, notes)";
            return false;
        }
        if (seen[k]) {
            error = where + "'" + std::string(key) + "' given twice";
            return false;
        }
        if (k == 2 && !valid_date(value)) {
            error = where + "birth_date '" + std::string(value) + "' is not YYYY-MM-DD";
            return false;
        }
        seen[k] = true;
        *fields[k] = value;
    }
    if (out.name.empty() || out.id.empty()) {
        error = file + ": missing " + (out.name.empty() ? "name" : "id");
        return false;
    }
    return true;
}

bool load_patient_record(const std::string& path, PatientRecord& out, std::string& error) {
    std::ifstream in(path);
    if (!in) {
        error = path + ": cannot open (" + std::strerror(errno) + ")";
        return false;
    }
    std::ostringstream text;
    text << in.rdbuf();
    return parse_patient_record(text.str(), path, out, error);
}

}  // namespace endotower::media
