// CalibrationStage: records in every trace line which calibration the firmware runs
// with, and runs the per-frame field-of-view check against it (a shifted centre or a
// different scope shows up in the trace the frame it happens). Trace member:
//   "calibration": {"file", "scope", "hash", "fov": "ok"|"shifted"|"scope_changed"|
//                   "unknown", "fov_shift_px"}
// Frames of another size than the calibration's: the circle is scaled when the aspect
// ratio matches, else the check reads "unknown". Allocates nothing per frame.
// With mask_outside_fov (set_mask), every pixel of the analysis frame outside the field
// of view is blackened after the check (mask_outside), so the stages after this one
// detect nothing there: the measured circle when the check found one, else the
// calibrated one; the trace member then also has "fov_mask": "measured"|"calibrated".
#pragma once

#include <optional>
#include <string>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/calibration/calibration_file.hpp"
#include "endotower/calibration/fov_monitor.hpp"

namespace endotower::calibration {

class CalibrationStage final : public app::AnalysisStage {
public:
    // `file` and `hash` name the calibration (content_hash of the file's bytes).
    CalibrationStage(const Calibration& calibration, std::string file, std::string hash);

    std::string_view name() const override { return "calibration"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;
    void set_mask(bool mask_outside_fov) { mask_ = mask_outside_fov; }

private:
    Calibration cal_;
    std::string file_, hash_;
    std::optional<FovMonitor> monitor_;
    FovCircle scaled_;  // the calibrated circle in this format's pixels
    bool mask_ = false;
};

}  // namespace endotower::calibration
