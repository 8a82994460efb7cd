#include "selftest_checks.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

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
    if (path.empty())
        return make(name, Check::Result::kSkip, "no paths.calibration in the board file");
    if (access(path.c_str(), R_OK) != 0)
        return make(name, Check::Result::kFail, system::errno_message("access", path, errno));
    cv::FileStorage fsr;
    try {
        if (!fsr.open(path, cv::FileStorage::READ))
            return make(name, Check::Result::kFail, path + ": not an OpenCV FileStorage file");
    } catch (const cv::Exception& e) {
        return make(name, Check::Result::kFail, path + ": not valid YAML/XML/JSON (" + e.msg + ")");
    }
    cv::Mat k, d;
    int w = 0, h = 0;
    try {
        fsr["camera_matrix"] >> k;
        fsr["distortion_coefficients"] >> d;
        fsr["image_width"] >> w;
        fsr["image_height"] >> h;
    } catch (const cv::Exception& e) {
        return make(name, Check::Result::kFail, path + ": " + e.msg);
    }
    if (k.rows != 3 || k.cols != 3)
        return make(name, Check::Result::kFail, path + ": camera_matrix missing or not 3x3");
    k.convertTo(k, CV_64F);
    const double fx = k.at<double>(0, 0), fy = k.at<double>(1, 1), cx = k.at<double>(0, 2),
                 cy = k.at<double>(1, 2);
    if (!(fx > 0) || !(fy > 0))
        return make(name, Check::Result::kFail,
                    path + ": camera_matrix focal lengths must be positive");
    if (w > 0 && h > 0 && (cx < 0 || cx > w || cy < 0 || cy > h))
        return make(name, Check::Result::kFail, path + ": principal point outside the image");
    const int n = static_cast<int>(d.total());
    if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
        return make(name, Check::Result::kFail,
                    path + ": distortion_coefficients must have 4, 5, 8, 12 or 14 values, has " +
                        std::to_string(n));
    char buf[128];
    std::snprintf(buf, sizeof buf, ": fx %.1f fy %.1f, %d distortion terms", fx, fy, n);
    return make(name, Check::Result::kPass, path + buf);
}

Check check_gesture_model(const std::string& path) {
    const char* name = "gesture model file";
    if (path.empty())
        return make(name, Check::Result::kSkip, "no paths.gesture_model in the board file");
    std::ifstream in(path);
    if (!in) return make(name, Check::Result::kFail, system::errno_message("open", path, errno));
    try {
        const YAML::Node n = YAML::Load(in);  // JSON is YAML too
        if (!n.IsMap() || n.size() == 0)
            return make(name, Check::Result::kFail, path + ": expected a non-empty mapping");
    } catch (const YAML::Exception& e) {
        return make(name, Check::Result::kFail,
                    path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
    }
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
