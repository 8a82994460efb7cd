// Selftest checks that need no device (files, storage) and the report: a pass/fail
// line per check, written as text and JSON (both atomic: temp file + rename).
#pragma once

#include <string>
#include <vector>

namespace endotower::firmware {

struct Check {
    enum class Result { kPass, kFail, kSkip };
    std::string name;  // "camera present", "display mode", ...
    Result result = Result::kFail;
    std::string detail;  // what was measured, or what is wrong and the fix
};

struct SelftestReport {
    std::string board;  // the board file
    std::string board_name;
    long long started_unix = 0;
    std::vector<Check> checks;

    bool passed() const;                     // no check failed
    std::string line(const Check& c) const;  // "PASS  camera present: /dev/video0 1920x1080"
    std::string text() const;
    std::string json() const;
};

// The directory exists (created if missing) and a file can be written into it
// atomically and removed again.
Check check_storage(const std::string& dir);
// OpenCV FileStorage (YAML/XML/JSON) with camera_matrix 3x3 (fx, fy > 0, cx, cy
// inside image_width x image_height when given) and distortion_coefficients of 4, 5,
// 8, 12 or 14 values, as cv::calibrateCamera writes them. Skip when `path` is "".
Check check_calibration(const std::string& path);
// The gesture model: a readable, non-empty YAML or JSON mapping. The project does
// not define its contents yet, so only the structure is checked. Skip when "".
Check check_gesture_model(const std::string& path);
// The gesture segmenter's pixel model (analysis.gestures.tool_model) loads as the gesture
// stage loads it (ToolLikelihood: header, size, checksum). Skip when "".
Check check_gesture_pixel_model(const std::string& path);

// Writes DIR/selftest.txt and DIR/selftest.json. False with `error`.
bool write_report(const std::string& dir, const SelftestReport& report, std::string& error);

}  // namespace endotower::firmware
