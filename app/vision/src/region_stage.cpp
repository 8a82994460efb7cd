#include "endotower/vision/region_stage.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace endotower::vision {

namespace {

// One colour per region id, opaque enough to read on tissue.
constexpr std::array<app::Rgba, 4> kColours{
    {{70, 240, 110, 230}, {80, 180, 255, 230}, {255, 200, 60, 230}, {240, 90, 240, 230}}};

void draw_region(app::OverlayCanvas& canvas, const RegionEstimate& e, int thickness) {
    cv::Mat rgba(canvas.height(), canvas.width(), CV_8UC4, canvas.row(0),
                 static_cast<std::size_t>(canvas.layer().stride));
    const app::Rgba c = kColours[static_cast<std::size_t>(e.id) % kColours.size()];
    const cv::Scalar colour(c.r, c.g, c.b, c.a);
    // Fixed-point vertices (4 fractional bits) keep the outline on the sub-pixel estimate.
    constexpr int kShift = 4;
    std::array<cv::Point, RegionEstimate::kMaxVertices> pts{};
    double cx = 0, cy = 0;
    for (std::size_t i = 0; i < e.vertices; ++i) {
        pts[i] = cv::Point(static_cast<int>(std::lround(e.polygon[i].x * 16)),
                           static_cast<int>(std::lround(e.polygon[i].y * 16)));
        cx += e.polygon[i].x / static_cast<double>(e.vertices);
        cy += e.polygon[i].y / static_cast<double>(e.vertices);
    }
    const cv::Point* outline = pts.data();
    const int count = static_cast<int>(e.vertices);
    cv::polylines(rgba, &outline, &count, 1, true, colour, thickness, cv::LINE_8, kShift);
    for (std::size_t i = 0; i < e.vertices; ++i)
        cv::circle(rgba, pts[i], (2 * thickness) << kShift, colour, cv::FILLED, cv::LINE_8, kShift);
    // The anchored marker: a cross at the vertices' mean.
    const int arm = 6 * thickness;
    const cv::Point centre(static_cast<int>(std::lround(cx)), static_cast<int>(std::lround(cy)));
    cv::line(rgba, centre - cv::Point(arm, 0), centre + cv::Point(arm, 0), colour, thickness);
    cv::line(rgba, centre - cv::Point(0, arm), centre + cv::Point(0, arm), colour, thickness);
    double x0 = cx, y0 = cy, x1 = cx, y1 = cy;
    for (std::size_t i = 0; i < e.vertices; ++i) {
        x0 = std::min(x0, e.polygon[i].x), x1 = std::max(x1, e.polygon[i].x);
        y0 = std::min(y0, e.polygon[i].y), y1 = std::max(y1, e.polygon[i].y);
    }
    const int pad = 3 * thickness + arm;
    // Clamp before converting: a polygon far outside the picture must not overflow int.
    auto clampi = [](double v) { return static_cast<int>(std::clamp(v, -1e6, 1e6)); };
    const int left = clampi(std::floor(x0)) - pad, top = clampi(std::floor(y0)) - pad;
    canvas.mark(
        {left, top, clampi(std::ceil(x1)) + pad - left + 1, clampi(std::ceil(y1)) + pad - top + 1});
}

}  // namespace

void RegionStage::schedule(RegionMark mark) {
    const auto at = std::upper_bound(
        pending_.begin() + static_cast<std::ptrdiff_t>(next_), pending_.end(), mark.frame,
        [](std::int64_t f, const RegionMark& m) { return f < m.frame; });
    pending_.insert(at, std::move(mark));
}

void RegionStage::configure(const hal::FrameFormat& format) {
    // Regions survive a format change: the tracker re-finds them by keyframe matching.
    thickness_ = std::max(2, format.height / 360);
}

void RegionStage::process(app::AnalysisContext& ctx) {
    const auto seq = static_cast<std::int64_t>(ctx.frame.sequence);
    std::string error;
    while (next_ < pending_.size() && pending_[next_].frame <= seq) {
        const RegionMark& m = pending_[next_++];
        if (!tracker_.mark(m.id, m.polygon, ctx.frame, error))
            errors_.push_back("frame " + std::to_string(seq) + ": " + error);
    }
    if (tracker_.size() == 0) return;
    const std::size_t n = tracker_.track(ctx.frame, estimates_);
    ctx.trace.begin_array("regions");
    for (std::size_t i = 0; i < n; ++i) {
        const RegionEstimate& e = estimates_[i];
        if (e.state == RegionState::kTracked && ctx.overlay.width() > 0)
            draw_region(ctx.overlay, e, thickness_);
        ctx.trace.begin_object().field("id", e.id).begin_array("polygon_px");
        for (std::size_t v = 0; v < e.vertices; ++v)
            ctx.trace.begin_array().value(e.polygon[v].x).value(e.polygon[v].y).end_array();
        ctx.trace.end_array()
            .field("state", to_string(e.state))
            .field("inliers", e.inliers)
            .end_object();
    }
    ctx.trace.end_array();
}

}  // namespace endotower::vision
