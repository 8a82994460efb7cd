// ToolTrackingStage: runs a ToolTracker on the analysis path, draws the tool cursor
// (a ring at each tip and a tick along the shaft) and writes the trace member
//   "tools": [{"id", "tip_px": [x, y], "head_px": [x, y], "axis_deg", "confidence",
//              "tip_mm": [x, y, z] or null}]
// in the coordinates of the input image. tip_mm is null until a calibrated camera
// is given (the calibration issue). Borrows the tracker.
#pragma once

#include <array>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

class ToolTrackingStage final : public app::AnalysisStage {
public:
    explicit ToolTrackingStage(ToolTracker& tracker) : tracker_(tracker) {}
    std::string_view name() const override { return "tool_tracking"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;

private:
    ToolTracker& tracker_;
    std::array<ToolEstimate, ToolTracker::kMaxTools> tools_{};
    int ring_radius_ = 12;
};

}  // namespace endotower::vision
