// Live target views for `endotower calibrate --live BOARD`: frames from the board's
// camera (its `capture:` V4L2 device; a board without one replays its `sim.input`
// on a virtual clock), the calibration target detected on the fly, and a view kept
// when it is new: its corners lie on average at least `novelty` x the image width
// from those of every view kept so far (the technician tilts and moves the target
// between views). One line per kept view, a progress line every few seconds while
// none is found.
// Parameters: views (15) to keep, min_interval_ms (250) of capture time between
// attempts (detection is slow on a large frame), novelty (0.02), timeout_s (180; live
// cameras only), save_dir ("" = none: the kept views as PNG, each written atomically).
#pragma once

#include <string>
#include <vector>

#include "endotower/calibration/target.hpp"

namespace endotower::firmware {

struct LiveViewOptions {
    std::string board;
    int views = 15;
    double min_interval_ms = 250;
    double novelty = 0.02;
    double timeout_s = 180;
    std::string save_dir;
};

struct LiveViews {
    std::vector<calibration::GrayImage> images;  // the kept frames, named "frame N"
    std::vector<calibration::View> views;        // their detections, same order
    std::string source;                          // the device or recording, for messages
    long frames = 0;                             // frames looked at
};

// False with `error` (exit 2 material: the board, the device and what went wrong) when
// the camera cannot be opened; true otherwise, even with few views (the caller decides).
bool capture_live_views(const LiveViewOptions& options, const calibration::TargetSpec& target,
                        LiveViews& out, std::string& error);

}  // namespace endotower::firmware
