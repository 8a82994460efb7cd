// Trace reader: parses a trace written by the pipeline (docs/trace.md) back into
// records, for `eval`, tests and tools. Not used on the per-frame path.
// Unknown members are kept as JSON text in `extra` so newer traces still load.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace endotower::app {

struct TraceInput {
    std::string kind;  // "press" | "release" | "wheel"
    int button = -1;   // press/release
    int delta = 0;     // wheel
    std::int64_t t_ns = 0;
};

struct TraceFormatChange {
    int width = 0, height = 0;
    std::string pixel_format;
};

struct TraceRecord {
    std::int64_t frame = 0, seq = 0;
    std::int64_t capture_ns = 0, present_ns = 0, latency_ns = 0;
    bool late = false;
    std::optional<std::int64_t> analysis_age;
    bool passthrough = false;
    std::optional<std::string> fault;
    std::vector<TraceInput> input;
    std::optional<TraceFormatChange> format_change;
    std::map<std::string, std::int64_t> stages_us;  // wall-clock durations per stage
    std::string extra;  // a JSON object of the members not listed above ("{}" if none)
};

// Parses one line; on error returns false with `error` saying which field is wrong.
bool parse_trace_line(const std::string& line, TraceRecord& out, std::string& error);
// Reads a whole trace; errors are "PATH:LINE: what".
bool read_trace(const std::string& path, std::vector<TraceRecord>& out, std::string& error);

}  // namespace endotower::app
