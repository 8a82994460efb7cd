#include "endotower/app/trace_reader.hpp"

#include <fstream>
#include <nlohmann/json.hpp>

namespace endotower::app {

namespace {

using nlohmann::json;

// Reads a required member of a given kind; false with a message naming it.
template <typename T>
bool get(const json& j, const char* key, T& out, std::string& error) {
    auto it = j.find(key);
    if (it == j.end()) {
        error = std::string("missing field '") + key + "'";
        return false;
    }
    if constexpr (std::is_same_v<T, bool>) {
        if (!it->is_boolean()) {
            error = std::string("field '") + key + "' must be true or false";
            return false;
        }
    } else {
        if (!it->is_number_integer()) {
            error = std::string("field '") + key + "' must be an integer";
            return false;
        }
    }
    out = it->get<T>();
    return true;
}

}  // namespace

bool parse_trace_line(const std::string& line, TraceRecord& r, std::string& error) {
    json j = json::parse(line, nullptr, false);
    if (j.is_discarded()) {
        error = "not valid JSON";
        return false;
    }
    if (!j.is_object()) {
        error = "a trace line must be a JSON object";
        return false;
    }
    r = TraceRecord{};
    if (!get(j, "frame", r.frame, error) || !get(j, "seq", r.seq, error) ||
        !get(j, "capture_ns", r.capture_ns, error) || !get(j, "present_ns", r.present_ns, error) ||
        !get(j, "latency_ns", r.latency_ns, error) || !get(j, "late", r.late, error) ||
        !get(j, "passthrough", r.passthrough, error))
        return false;
    if (auto it = j.find("analysis_age"); it != j.end() && !it->is_null()) {
        if (!it->is_number_integer()) {
            error = "field 'analysis_age' must be an integer or null";
            return false;
        }
        r.analysis_age = it->get<std::int64_t>();
    }
    if (auto it = j.find("fault"); it != j.end() && !it->is_null()) {
        if (!it->is_string()) {
            error = "field 'fault' must be a string or null";
            return false;
        }
        r.fault = it->get<std::string>();
    }
    if (auto it = j.find("input"); it != j.end()) {
        if (!it->is_array()) {
            error = "field 'input' must be an array";
            return false;
        }
        for (const json& e : *it) {
            TraceInput in;
            if (!e.is_object() || !e.contains("kind") || !e["kind"].is_string()) {
                error = "an 'input' element needs a string 'kind'";
                return false;
            }
            in.kind = e["kind"].get<std::string>();
            if (!get(e, "t_ns", in.t_ns, error)) return false;
            if (in.kind == "wheel") {
                if (!get(e, "delta", in.delta, error)) return false;
            } else if (!get(e, "button", in.button, error)) {
                return false;
            }
            r.input.push_back(std::move(in));
        }
    }
    if (auto it = j.find("format_change"); it != j.end()) {
        TraceFormatChange fc;
        if (!it->is_object() || !get(*it, "width", fc.width, error) ||
            !get(*it, "height", fc.height, error) || !it->contains("pixel_format")) {
            if (error.empty()) error = "field 'format_change' needs width, height, pixel_format";
            return false;
        }
        fc.pixel_format = (*it)["pixel_format"].get<std::string>();
        r.format_change = fc;
    }
    if (auto it = j.find("stages_us"); it != j.end()) {
        if (!it->is_object()) {
            error = "field 'stages_us' must be an object";
            return false;
        }
        for (const auto& [k, v] : it->items()) {
            if (!v.is_number_integer()) {
                error = "field 'stages_us." + k + "' must be an integer";
                return false;
            }
            r.stages_us[k] = v.get<std::int64_t>();
        }
    }
    for (const char* known : {"stages_us", "frame", "seq", "capture_ns", "present_ns", "latency_ns", "late",
                              "analysis_age", "passthrough", "fault", "input", "format_change"})
        j.erase(known);
    r.extra = j.dump();
    return true;
}

bool read_trace(const std::string& path, std::vector<TraceRecord>& out, std::string& error) {
    std::ifstream in(path);
    if (!in) {
        error = "cannot read trace: " + path;
        return false;
    }
    out.clear();
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        if (line.empty()) continue;
        TraceRecord r;
        std::string what;
        if (!parse_trace_line(line, r, what)) {
            error = path + ":" + std::to_string(number) + ": " + what;
            return false;
        }
        out.push_back(std::move(r));
    }
    return true;
}

}  // namespace endotower::app
