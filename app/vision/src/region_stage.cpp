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

void RegionStage::enable_tool_marking(const RegionMarkerParams& params,
                                      std::function<bool(Point2&)> tip) {
    marker_.set_params(params);
    tip_ = std::move(tip);
}

void RegionStage::mark_with_tool(app::AnalysisContext& ctx) {
    Point2 tip;
    const bool has_tip = tip_(tip);
    const char* event = nullptr;
    std::span<const hal::ControlEvent> events = ctx.events;
    if (!marker_.marking()) {
        // A long press starts an outline; what follows it in this frame is its.
        for (std::size_t i = 0; i < events.size(); ++i)
            if (events[i].button == 0 && events[i].kind == hal::ControlEvent::Kind::kLongPress) {
                marker_.begin();
                event = "started";
                events = events.subspan(i + 1);
                break;
            }
    }
    switch (marker_.update(has_tip ? &tip : nullptr, events, ctx.frame.capture_ns)) {
        case RegionMarker::Event::kVertex:
            event = "vertex";
            break;
        case RegionMarker::Event::kCancelled:
            event = "cancelled";
            break;
        case RegionMarker::Event::kClosed: {
            event = "closed";
            std::array<Point2, RegionMarker::kMaxVertices> poly{};
            std::size_t n = 0;
            marker_.take_polygon(poly, n);
            std::string error;
            if (tracker_.mark(next_id_, std::span<const Point2>(poly.data(), n), ctx.frame, error))
                ++next_id_;
            else {
                event = "refused";
                errors_.push_back("frame " + std::to_string(ctx.frame.sequence) + ": " + error);
            }
            break;
        }
        default:
            break;
    }
    const auto vertices = marker_.vertices();
    if (marker_.marking() && ctx.overlay.width() > 0) {
        cv::Mat rgba(ctx.overlay.height(), ctx.overlay.width(), CV_8UC4, ctx.overlay.row(0),
                     static_cast<std::size_t>(ctx.overlay.layer().stride));
        const cv::Scalar colour(255, 255, 255, 230);
        double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
        auto grow = [&](Point2 p) {
            x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x),
            y1 = std::max(y1, p.y);
        };
        for (std::size_t i = 0; i < vertices.size(); ++i) {
            const cv::Point a(static_cast<int>(vertices[i].x), static_cast<int>(vertices[i].y));
            cv::circle(rgba, a, 2 * thickness_, colour, cv::FILLED);
            if (i > 0)
                cv::line(rgba,
                         cv::Point(static_cast<int>(vertices[i - 1].x),
                                   static_cast<int>(vertices[i - 1].y)),
                         a, colour, thickness_);
            grow(vertices[i]);
        }
        if (has_tip) {
            // The dwell: an arc that fills as the tip holds still.
            const int r = 8 * thickness_;
            const cv::Point c(static_cast<int>(tip.x), static_cast<int>(tip.y));
            cv::ellipse(rgba, c, {r, r}, -90, 0, 360 * marker_.dwell_progress(), colour,
                        thickness_);
            grow({tip.x - r, tip.y - r});
            grow({tip.x + r, tip.y + r});
        }
        if (x1 >= x0) {
            const int pad = 4 * thickness_;
            auto clampi = [](double v) { return static_cast<int>(std::clamp(v, -1e6, 1e6)); };
            const int left = clampi(std::floor(x0)) - pad, top = clampi(std::floor(y0)) - pad;
            ctx.overlay.mark({left, top, clampi(std::ceil(x1)) + pad - left + 1,
                              clampi(std::ceil(y1)) + pad - top + 1});
        }
    }
    ctx.trace.begin_object("region_marking")
        .field("marking", marker_.marking())
        .begin_array("vertices");
    for (const Point2& v : vertices) ctx.trace.begin_array().value(v.x).value(v.y).end_array();
    ctx.trace.end_array();
    if (event != nullptr)
        ctx.trace.field("event", event);
    else
        ctx.trace.null_field("event");
    ctx.trace.end_object();
}

const RegionOverlay& RegionStage::overlay(int id) const {
    for (const auto& [i, o] : overlays_)
        if (i == id) return o;
    return tool_overlay_;
}

void RegionStage::schedule(RegionMark mark) {
    next_id_ = std::max(next_id_, mark.id + 1);  // regions marked with the tool come after
    overlays_.emplace_back(mark.id, mark.overlay);
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
    if (tip_) mark_with_tool(ctx);
    count_ = 0;
    if (tracker_.size() == 0) return;
    const std::size_t n = tracker_.track(ctx.frame, estimates_);
    count_ = n;
    ctx.trace.begin_array("regions");
    for (std::size_t i = 0; i < n; ++i) {
        const RegionEstimate& e = estimates_[i];
        if (e.state == RegionState::kTracked && ctx.overlay.width() > 0 &&
            overlay(e.id).kind == RegionOverlayKind::kMarkers)
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
