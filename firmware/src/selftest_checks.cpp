#include "selftest_checks.hpp"

#include "endotower/calibration/calibration_file.hpp"
#include "endotower/vision/gesture_classifier.hpp"
#include "endotower/vision/tool_likelihood.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "endotower/system/syscall.hpp"

namespace endotower::firmware {

namespace fs = std::filesystem;

namespace {
Check make(const char* name, Check::Result r, std::string detail) {
    return {name, r, std::move(detail)};
}
const char* result_name(Check::Result r) {
    return r == Check::Result::kPass ? "PASS" : r == Check::Result::kFail ? "FAIL" : "SKIP";
}
}  // namespace

bool SelftestReport::passed() const {
    for (const Check& c : checks)
        if (c.result == Check::Result::kFail) return false;
    return true;
}

std::string SelftestReport::line(const Check& c) const {
    return std::string(result_name(c.result)) + "  " + c.name +
           (c.detail.empty() ? "" : ": " + c.detail);
}

std::string SelftestReport::text() const {
    std::string s = "endotower selftest, board " + board_name + " (" + board + ")\n";
    for (const Check& c : checks) s += line(c) + "\n";
    s += std::string("overall: ") + (passed() ? "PASS" : "FAIL") + "\n";
    return s;
}

std::string SelftestReport::json() const {
    nlohmann::json j;
    j["board"] = board;
    j["board_name"] = board_name;
    j["started_unix"] = started_unix;
    j["passed"] = passed();
    j["checks"] = nlohmann::json::array();
    for (const Check& c : checks)
        j["checks"].push_back(
            {{"name", c.name}, {"result", result_name(c.result)}, {"detail", c.detail}});
    return j.dump(2) + "\n";
}

Check check_storage(const std::string& dir) {
    const char* name = "storage writable";
    if (dir.empty()) return make(name, Check::Result::kSkip, "no paths.storage in the board file");
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir))
        return make(name, Check::Result::kFail,
                    dir + ": cannot create the directory (" + ec.message() + ")");
    const std::string probe = (fs::path(dir) / ".selftest-probe").string();
    std::string error;
    if (!system::write_file_atomic(probe, "endotower selftest probe\n", error))
        return make(name, Check::Result::kFail,
                    error + "; fix: make " + dir + " writable by the endotower user");
    std::ifstream in(probe);
    std::string back;
    std::getline(in, back);
    fs::remove(probe, ec);
    if (back != "endotower selftest probe")
        return make(name, Check::Result::kFail,
                    probe + ": read back differs from what was written");
    return make(name, Check::Result::kPass, dir);
}

Check check_calibration(const std::string& path) {
    const char* name = "calibration file";
    if (path.empty()) return make(name, Check::Result::kSkip, "no calibration in the board file");
    if (access(path.c_str(), R_OK) != 0)
        return make(name, Check::Result::kFail, system::errno_message("access", path, errno));
    // The same validation the firmware applies when it loads the file (docs/calibration.md).
    calibration::Calibration c;
    std::string error;
    if (!calibration::load_calibration(path, c, error)) return make(name, Check::Result::kFail, error);
    char buf[160];
    std::snprintf(buf, sizeof buf, ": scope %s, %dx%d, fx %.1f fy %.1f, rms %.3f px", c.scope.c_str(), c.width,
                  c.height, c.fx, c.fy, c.rms);
    return make(name, Check::Result::kPass, path + buf);
}

Check check_gesture_model(const std::string& path) {
    const char* name = "gesture model file";
    if (path.empty()) return make(name, Check::Result::kSkip, "no analysis.gestures.model in the board file");
    // The classifier's own loader: header, checksum and network shape (docs/gestures.md).
    vision::GestureClassifier classifier;
    std::string error;
    if (!classifier.load(path, error)) return make(name, Check::Result::kFail, error);
    return make(name, Check::Result::kPass, path);
}

Check check_gesture_pixel_model(const std::string& path) {
    const char* name = "gesture pixel model file";
    if (path.empty())
        return make(name, Check::Result::kSkip,
                    "no analysis.gestures.tool_model in the board file (the gestures use "
                    "analysis.tool_model)");
    // ToolLikelihood's own loader: header, size and checksum (docs/tracking.md).
    vision::ToolLikelihood model;
    std::string error;
    if (!model.load(path, error)) return make(name, Check::Result::kFail, error);
    return make(name, Check::Result::kPass, path);
}

bool write_report(const std::string& dir, const SelftestReport& report, std::string& error) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    return system::write_file_atomic((fs::path(dir) / "selftest.txt").string(), report.text(),
                                     error) &&
           system::write_file_atomic((fs::path(dir) / "selftest.json").string(), report.json(),
                                     error);
}

}  // namespace endotower::firmware
