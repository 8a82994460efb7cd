// ToolTrackingStage: runs a ToolTracker on the analysis path, draws the tool cursor
// (a ring at each tip and a tick along the shaft) and writes the trace member
//   "tools": [{"id", "tip_px": [x, y], "head_px": [x, y], "axis_deg", "confidence",
//              "tip_mm": [x, y, z] or null}]
// in the coordinates of the input image. With a calibrated camera (set_camera), each
// tool's edges and tip are undistorted and its 3-D pose reconstructed (ToolPose,
// eq. 4.22-4.27) with the configured shaft diameter: "tip_mm" is the tip in the camera
// frame (mm), and "pose": {"axis_dir", "yaw_deg", "pitch_deg", "depth_sigma_mm",
// "confidence"} is added; without one (or when the pose is degenerate) tip_mm is null.
// Borrows the tracker. tool_count()/tool()/pose(): this frame's tools for the stages
// after it in the chain (the SCI); pose(i).valid is false without a 3-D pose.
#pragma once

#include <array>
#include <functional>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/vision/tool_pose.hpp"
#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

class ToolTrackingStage final : public app::AnalysisStage {
public:
    explicit ToolTrackingStage(ToolTracker& tracker) : tracker_(tracker) {}
    std::string_view name() const override { return "tool_tracking"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;
    // `undistort` maps a pixel of the input image to the corrected (pinhole) image of
    // `camera`; called a few times per tool and frame, it must not allocate.
    void set_camera(const PinholeCamera& camera, std::function<Point2(Point2)> undistort, double diameter_mm);
    std::size_t tool_count() const { return count_; }
    const ToolEstimate& tool(std::size_t i) const { return tools_[i]; }
    const ToolPose& pose(std::size_t i) const { return poses_[i]; }

private:
    PinholeCamera camera_{};
    std::function<Point2(Point2)> undistort_;
    double diameter_mm_ = 0;
    ToolTracker& tracker_;
    std::array<ToolEstimate, ToolTracker::kMaxTools> tools_{};
    std::array<ToolPose, ToolTracker::kMaxTools> poses_{};
    std::size_t count_ = 0;
    int ring_radius_ = 12;
};

}  // namespace endotower::vision
