// OpenCV's standard calibration (Zhang's method) beside the book's: pinhole
// (k1 k2 p1 p2 k3) or fisheye (k1..k4) from views of a planar target, with automatic
// rejection of inconsistent views.
//
// Rejection (leave-one-out): calibrate with every view; the (up to three) views whose
// error exceeds twice the median view's are suspects, each left out in turn. The
// suspect whose absence helps most is dropped when leaving it out lowers the RMS by
// more than a third AND, under the calibration of the others (its pose
// re-estimated), its own RMS is more than 3x the others' median and above 0.5 px.
// Repeated while >= 4 views remain. Each dropped view keeps the figures that
// condemned it, for the report.
#pragma once

#include <string>
#include <vector>

#include "endotower/calibration/target.hpp"

namespace endotower::calibration {

enum class LensModel { kPinhole, kFisheye, kBook };
const char* to_string(LensModel m);
bool parse_lens_model(const std::string& s, LensModel& out);

struct ZhangResult {
    LensModel model = LensModel::kPinhole;
    int width = 0, height = 0;
    double fx = 0, fy = 0, cx = 0, cy = 0;
    std::vector<double> distortion;  // pinhole: k1 k2 p1 p2 k3; fisheye: k1 k2 k3 k4
    double rms = 0;                  // px, over all points of the kept views
    struct ViewError {
        std::string name;
        double rms = 0;
    };
    std::vector<ViewError> views;  // kept views
    struct Dropped {
        std::string name, reason;
    };
    std::vector<Dropped> dropped;
    // Distance error: adjacent target points back-projected onto the target plane
    // (each view's pose), mean |measured - true| distance, mm (target units).
    double spacing_error = 0;
};

struct ZhangOptions {
    bool zero_tangent = false;        // pinhole: p1 = p2 = 0 (OpenCV's CALIB_ZERO_TANGENT_DIST)
    bool reject_inconsistent = true;  // the leave-one-out rejection above
};

// Calibrates from `views` of images `width` x `height`. False with `error` when
// fewer than 3 views, a view has fewer than 6 points, OpenCV fails, or the focal
// length is implausible (over 10x the image size: a field of view under ~6 degrees,
// the signature of a target layout that does not match the printed grid).
bool calibrate_zhang(const std::vector<View>& views, int width, int height, LensModel model,
                     ZhangResult& out, std::string& error, ZhangOptions options = {});

// Reprojection RMS (px) of `views` under given intrinsics (each view's pose solved).
double reprojection_rms(const std::vector<View>& views, const ZhangResult& camera);

}  // namespace endotower::calibration
