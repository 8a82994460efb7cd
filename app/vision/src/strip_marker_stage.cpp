#include "endotower/vision/strip_marker_stage.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::vision {

void StripMarkerStage::configure(const hal::FrameFormat& format) {
    tracker_.configure(format);
    arm_ = std::max(4, format.height / 60);
}

void StripMarkerStage::process(app::AnalysisContext& ctx) {
    const std::size_t n = tracker_.track(
        ctx.frame, std::span<StripMarker, StripMarkerTracker::kMaxMarkers>(markers_));
    const int thick = std::max(1, ctx.frame.format.height / 360);
    const app::Rgba colour{255, 210, 40, 230};
    ctx.trace.begin_array("markers");
    for (std::size_t i = 0; i < n; ++i) {
        const StripMarker& m = markers_[i];
        // The cross at E: the point the book tracks.
        const int x = static_cast<int>(std::lround(m.e.x)),
                  y = static_cast<int>(std::lround(m.e.y));
        ctx.overlay.fill({x - arm_, y - thick / 2, 2 * arm_ + 1, thick + 1}, colour);
        ctx.overlay.fill({x - thick / 2, y - arm_, thick + 1, 2 * arm_ + 1}, colour);
        ctx.trace.begin_object()
            .begin_array("center_px")
            .value(m.e.x)
            .value(m.e.y)
            .end_array()
            .begin_array("corners_px");
        for (const Point2& c : {m.a, m.b, m.c, m.d})
            ctx.trace.begin_array().value(c.x).value(c.y).end_array();
        ctx.trace.end_array().field("diameter_px", m.diameter_px).field("strips", m.strips);
        if (m.located) {
            ctx.trace.field("depth_mm", m.depth_mm);
            ctx.trace.begin_array("tip_mm")
                .value(m.e_mm.x)
                .value(m.e_mm.y)
                .value(m.e_mm.z)
                .end_array();
        } else {
            ctx.trace.null_field("depth_mm").null_field("tip_mm");
        }
        ctx.trace.end_object();
    }
    ctx.trace.end_array();
}

}  // namespace endotower::vision
