// Builders for hand-made traces and ground truth in the eval tests.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "endotower_command.hpp"
#include "scratch_dir.hpp"

namespace endotower::eval::test {

namespace fs = std::filesystem;

// A trace line: the base members every line has, plus `analysis` members ("" = none),
// e.g. R"("tools":[...])".
inline std::string trace_line(int frame, const std::string& analysis = "") {
    std::string s = "{\"frame\":" + std::to_string(frame) + ",\"seq\":" + std::to_string(frame) +
                    ",\"capture_ns\":0,\"present_ns\":0,\"latency_ns\":0,\"late\":false,"
                    "\"passthrough\":false";
    if (!analysis.empty()) s += "," + analysis;
    return s + "}";
}

// A trace tool.
inline std::string ttool(int id, double x, double y, double axis, double hx = -1, double hy = -1,
                         const std::string& tip_mm = "null") {
    char b[256];
    std::snprintf(
        b, sizeof b,
        R"({"id":%d,"tip_px":[%g,%g],"head_px":[%g,%g],"axis_deg":%g,"confidence":0.9,"tip_mm":%s})",
        id, x, y, hx < 0 ? x : hx, hy < 0 ? y : hy, axis, tip_mm.c_str());
    return b;
}

// A truth tool (visible unless told), width in px.
inline std::string gtool(int id, double x, double y, double axis, double width, bool visible = true,
                         const std::string& extra = "") {
    char b[320];
    std::snprintf(
        b, sizeof b,
        R"({"id":%d,"visible":%s,"tip_px":[%g,%g],"head_px":[%g,%g],"axis_deg":%g,"width_px":%g%s})",
        id, visible ? "true" : "false", x, y, x, y, axis, width, extra.c_str());
    return b;
}

inline std::string truth_line(int frame, const std::string& tools, const std::string& more = "") {
    std::string s = "{\"frame\":" + std::to_string(frame) + ",\"tools\":[" + tools + "]";
    if (!more.empty()) s += "," + more;
    return s + "}";
}

// A fresh directory under the test's temp dir.
inline fs::path temp_dir(const std::string& name) {
    return endotower::test::scratch_dir("eval_" + name);
}

inline std::string write_lines(const fs::path& path, const std::vector<std::string>& lines) {
    std::ofstream out(path);
    for (const std::string& l : lines) out << l << "\n";
    return path.string();
}

using endotower::test::CommandRun;
// `endotower eval ARGS` with stdout and stderr captured, and its exit status.
inline CommandRun run_eval(const std::string& args) {
    return endotower::test::run_endotower("eval " + args);
}

}  // namespace endotower::eval::test
