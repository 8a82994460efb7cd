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

void ToolTrackingStage::configure(const hal::FrameFormat& format) {
    tracker_.configure(format);
    ring_radius_ = std::max(6, format.height / 45);
}

void ToolTrackingStage::process(app::AnalysisContext& ctx) {
    const std::size_t n = tracker_.track(ctx.frame, std::span<ToolEstimate, ToolTracker::kMaxTools>(tools_));
    const int thick = std::max(2, ctx.frame.format.height / 270);
    ctx.trace.begin_array("tools");
    for (std::size_t i = 0; i < n; ++i) {
        const ToolEstimate& t = tools_[i];
        // The cursor: the surgeon's pointer is the tool tip.
        const app::Rgba colour = t.id % 2 == 0 ? app::Rgba{60, 230, 120, 230} : app::Rgba{80, 170, 255, 230};
        draw_ring(ctx.overlay, t.tip, ring_radius_, thick, colour);
        ctx.trace.begin_object()
            .field("id", t.id)
            .begin_array("tip_px").value(t.tip.x).value(t.tip.y).end_array()
            .begin_array("head_px").value(t.head.x).value(t.head.y).end_array()
            .field("axis_deg", t.axis_deg)
            .field("confidence", t.confidence)
            .null_field("tip_mm")
            .end_object();
    }
    ctx.trace.end_array();
}

}  // namespace endotower::vision
