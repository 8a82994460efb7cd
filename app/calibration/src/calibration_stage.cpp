#include "endotower/calibration/calibration_stage.hpp"

#include <cmath>

namespace endotower::calibration {

CalibrationStage::CalibrationStage(const Calibration& calibration, std::string file,
                                   std::string hash)
    : cal_(calibration), file_(std::move(file)), hash_(std::move(hash)) {}

void CalibrationStage::configure(const hal::FrameFormat& format) {
    monitor_.reset();
    if (!cal_.fov.valid() || cal_.width <= 0 || cal_.height <= 0) return;
    const double sx = static_cast<double>(format.width) / cal_.width;
    const double sy = static_cast<double>(format.height) / cal_.height;
    if (std::abs(sx - sy) > 0.01 * sx) return;  // another aspect ratio: no like-for-like circle
    scaled_ = FovCircle{cal_.fov.cx * sx, cal_.fov.cy * sy, cal_.fov.radius * sx};
    monitor_.emplace(scaled_);
}

void CalibrationStage::process(app::AnalysisContext& ctx) {
    FovCheck check;
    if (monitor_) check = monitor_->check(ctx.frame);
    ctx.trace.begin_object("calibration")
        .field("file", file_)
        .field("scope", cal_.scope)
        .field("hash", hash_)
        .field("fov", to_string(check.status));
    if (check.status != FovStatus::kUnknown)
        ctx.trace.field("fov_shift_px", std::round(check.shift_px * 100) / 100);
    if (mask_ && monitor_) {
        // A measured circle of another radius is another scope: keep to the calibrated one.
        const bool measured = check.status == FovStatus::kOk || check.status == FovStatus::kShifted;
        FovCircle c = measured ? check.circle : scaled_;
        c.radius += 1.0;  // the rim's own pixels stay
        mask_outside(ctx.frame, c);
        ctx.trace.field("fov_mask", measured ? "measured" : "calibrated");
    }
    ctx.trace.end_object();
}

}  // namespace endotower::calibration
