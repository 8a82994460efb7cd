#include "endotower/vision/tool_tracking_stage.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::vision {

namespace {

// Anti-aliasing is not needed for a cursor; a plain ring, 2 px thick per 540 rows.
void draw_ring(app::OverlayCanvas& c, Point2 centre, int radius, int thickness, app::Rgba colour) {
    const int cx = static_cast<int>(std::lround(centre.x)), cy = static_cast<int>(std::lround(centre.y));
    const int r2o = radius * radius, r2i = (radius - thickness) * (radius - thickness);
    for (int y = std::max(0, cy - radius); y <= std::min(c.height() - 1, cy + radius); ++y) {
        std::uint8_t* row = c.row(y);
        for (int x = std::max(0, cx - radius); x <= std::min(c.width() - 1, cx + radius); ++x) {
            const int d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
            if (d2 > r2o || d2 < r2i) continue;
            std::uint8_t* p = row + 4 * x;
            p[0] = colour.r, p[1] = colour.g, p[2] = colour.b, p[3] = colour.a;
        }
    }
    c.mark({cx - radius, cy - radius, 2 * radius + 1, 2 * radius + 1});
}

}  // namespace

void ToolTrackingStage::set_camera(const PinholeCamera& camera, std::function<Point2(Point2)> undistort,
                                   double diameter_mm) {
    camera_ = camera;
    undistort_ = std::move(undistort);
    diameter_mm_ = diameter_mm;
}

void ToolTrackingStage::configure(const hal::FrameFormat& format) {
    tracker_.configure(format);
    ring_radius_ = std::max(6, format.height / 45);
}

void ToolTrackingStage::process(app::AnalysisContext& ctx) {
    const std::size_t n = tracker_.track(ctx.frame, std::span<ToolEstimate, ToolTracker::kMaxTools>(tools_));
    count_ = n;
    const int thick = std::max(2, ctx.frame.format.height / 270);
    ctx.trace.begin_array("tools");
    for (std::size_t i = 0; i < n; ++i) {
        const ToolEstimate& t = tools_[i];
        // The cursor: the surgeon's pointer is the tool tip.
        const app::Rgba colour = t.id % 2 == 0 ? app::Rgba{60, 230, 120, 230} : app::Rgba{80, 170, 255, 230};
        draw_ring(ctx.overlay, t.tip, ring_radius_, thick, colour);
        ToolPose& pose = poses_[i];
        pose = ToolPose{};
        if (undistort_ && diameter_mm_ > 0 && t.edges.found) {
            const auto u = [&](Point2 p) { return undistort_(p); };
            pose = reconstruct_tool_pose(camera_, {u(t.edges.e1.a), u(t.edges.e1.b)}, {u(t.edges.e2.a), u(t.edges.e2.b)},
                                         u(t.tip), u(t.edges.midline.b), diameter_mm_);
        }
        ctx.trace.begin_object()
            .field("id", t.id)
            .begin_array("tip_px").value(t.tip.x).value(t.tip.y).end_array()
            .begin_array("head_px").value(t.head.x).value(t.head.y).end_array()
            .field("axis_deg", t.axis_deg)
            .field("confidence", t.confidence);
        if (pose.valid) {
            ctx.trace.begin_array("tip_mm").value(pose.tip_mm.x).value(pose.tip_mm.y).value(pose.tip_mm.z).end_array();
            ctx.trace.begin_object("pose")
                .begin_array("axis_dir").value(pose.axis_dir.x).value(pose.axis_dir.y).value(pose.axis_dir.z).end_array()
                .field("yaw_deg", pose.yaw_deg)
                .field("pitch_deg", pose.pitch_deg)
                .field("depth_sigma_mm", pose.depth_sigma_mm)
                .field("confidence", pose.confidence)
                .end_object();
        } else {
            ctx.trace.null_field("tip_mm");
        }
        ctx.trace.end_object();
    }
    ctx.trace.end_array();
}

}  // namespace endotower::vision
