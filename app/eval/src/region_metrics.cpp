#include "endotower/eval/region_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

#include "endotower/eval/assignment.hpp"

namespace endotower::eval {

const char* region_class_name(RegionClass c) {
    switch (c) {
        case RegionClass::kGood: return "GOOD";
        case RegionClass::kOk: return "OK";
        case RegionClass::kFail: break;
    }
    return "FAIL";
}

double polygon_area(const std::vector<Point2>& p) {
    double a = 0;
    for (std::size_t i = 0, n = p.size(); i < n; ++i) {
        const Point2& u = p[i];
        const Point2& v = p[(i + 1) % n];
        a += u.x * v.y - v.x * u.y;
    }
    return std::abs(a) / 2;
}

namespace {

std::vector<cv::Point2f> to_cv(const std::vector<Point2>& p) {
    std::vector<cv::Point2f> out;
    for (const Point2& q : p) out.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y));
    return out;
}

// Non-convex polygons: both filled on one grid (sub-pixel vertices through `shift`),
// the intersection counted in cells.
double raster_intersection(const std::vector<Point2>& a, const std::vector<Point2>& b) {
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    for (const auto* poly : {&a, &b})
        for (const Point2& p : *poly) {
            x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
            x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
        }
    const double extent = std::max(x1 - x0, y1 - y0);
    if (!(extent > 0)) return 0;
    const double scale = std::min(4.0, 2048.0 / extent);  // cells per pixel
    const int w = static_cast<int>(std::ceil((x1 - x0) * scale)) + 2;
    const int h = static_cast<int>(std::ceil((y1 - y0) * scale)) + 2;
    constexpr int kShift = 4;
    auto fill = [&](const std::vector<Point2>& p) {
        cv::Mat m = cv::Mat::zeros(h, w, CV_8U);
        std::vector<cv::Point> pts;
        for (const Point2& q : p)
            pts.emplace_back(static_cast<int>(std::lround((q.x - x0) * scale * (1 << kShift))),
                             static_cast<int>(std::lround((q.y - y0) * scale * (1 << kShift))));
        cv::fillPoly(m, std::vector<std::vector<cv::Point>>{pts}, cv::Scalar(1), cv::LINE_8, kShift);
        return m;
    };
    const cv::Mat both = fill(a) & fill(b);
    return cv::countNonZero(both) / (scale * scale);
}

double signed_area(const std::vector<Point2>& p) {
    double a = 0;
    for (std::size_t i = 0, n = p.size(); i < n; ++i)
        a += p[i].x * p[(i + 1) % n].y - p[(i + 1) % n].x * p[i].y;
    return a / 2;
}

// Sutherland-Hodgman: `subject` (any simple polygon) clipped by the convex `clip`.
// The result may carry zero-width bridges where a non-convex subject is cut in two;
// they add no area, so its shoelace area is the exact intersection area.
double clipped_area(const std::vector<Point2>& subject, const std::vector<Point2>& clip) {
    const double orient = signed_area(clip) >= 0 ? 1.0 : -1.0;
    std::vector<Point2> out = subject, in;
    for (std::size_t i = 0, n = clip.size(); i < n && !out.empty(); ++i) {
        const Point2 a = clip[i], b = clip[(i + 1) % n];
        auto side = [&](Point2 p) { return orient * ((b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)); };
        in.swap(out);
        out.clear();
        for (std::size_t j = 0, m = in.size(); j < m; ++j) {
            const Point2 p = in[j], q = in[(j + 1) % m];
            const double sp = side(p), sq = side(q);
            if (sp >= 0) out.push_back(p);
            if ((sp >= 0) != (sq >= 0)) {
                const double t = sp / (sp - sq);
                out.push_back({p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)});
            }
        }
    }
    return out.size() < 3 ? 0.0 : std::abs(signed_area(out));
}

}  // namespace

double polygon_intersection_area(const std::vector<Point2>& a, const std::vector<Point2>& b) {
    if (a.size() < 3 || b.size() < 3) return 0;
    const std::vector<cv::Point2f> ca = to_cv(a), cb = to_cv(b);
    // Exact when either polygon is convex; rasterised only when neither is.
    if (cv::isContourConvex(cb)) return clipped_area(a, b);
    if (cv::isContourConvex(ca)) return clipped_area(b, a);
    return raster_intersection(a, b);
}

RegionMatch classify_region(const std::vector<Point2>& truth, const std::vector<Point2>* trace,
                            const RegionRule& rule) {
    RegionMatch m;
    const double at = polygon_area(truth);
    if (trace == nullptr || trace->size() < 3 || !(at > 0)) return m;
    const double ar = polygon_area(*trace);
    if (trace->size() == truth.size()) {
        double sum = 0;
        for (std::size_t i = 0; i < truth.size(); ++i)
            sum += std::hypot(truth[i].x - (*trace)[i].x, truth[i].y - (*trace)[i].y);
        m.corner_error_px = sum / static_cast<double>(truth.size());
    }
    if (!(ar > 0)) return m;
    const double inter = std::min({polygon_intersection_area(truth, *trace), at, ar});
    m.iou = inter / (at + ar - inter);
    m.coverage = inter / at;
    const bool corners_ok =
        !m.corner_error_px || *m.corner_error_px <= rule.good_corner_fraction * std::sqrt(at);
    if (m.coverage >= rule.good_coverage && m.iou >= rule.good_iou && corners_ok)
        m.cls = RegionClass::kGood;
    else if (m.iou >= rule.ok_iou || (m.coverage >= rule.ok_coverage && ar <= rule.ok_max_area_ratio * at))
        m.cls = RegionClass::kOk;
    return m;
}

RegionScore score_regions(const std::vector<TruthFrame>& truth,
                          const std::vector<AnalysisFrame>& trace, const RegionRule& rule) {
    RegionScore s;
    std::unordered_map<std::int64_t, const AnalysisFrame*> by_frame;
    bool trace_has = false, truth_has = false;
    for (const AnalysisFrame& a : trace) {
        by_frame[a.frame] = &a;
        trace_has = trace_has || a.has_regions;
    }
    for (const TruthFrame& f : truth) truth_has = truth_has || !f.regions.empty();
    s.present = trace_has && truth_has;
    if (!s.present) return s;
    double corner_sum = 0;
    for (const TruthFrame& f : truth) {
        if (f.regions.empty()) continue;
        std::vector<const TraceRegion*> found;
        if (auto it = by_frame.find(f.frame); it != by_frame.end())
            for (const TraceRegion& r : it->second->regions)
                if (r.tracked) found.push_back(&r);
        // One to one by greatest IoU; equal ids break ties.
        const int rows = static_cast<int>(f.regions.size()), cols = static_cast<int>(found.size());
        std::vector<double> cost(static_cast<std::size_t>(rows) * cols);
        std::vector<RegionMatch> matches(cost.size());
        for (int r = 0; r < rows; ++r)
            for (int c = 0; c < cols; ++c) {
                matches[r * cols + c] = classify_region(f.regions[r].polygon_px, &found[c]->polygon_px, rule);
                cost[r * cols + c] = 1.0 - matches[r * cols + c].iou +
                                     (f.regions[r].id == found[c]->id ? 0.0 : 1e-6);
            }
        const std::vector<int> pick = assign_min_cost(cost, rows, cols);
        for (int r = 0; r < rows; ++r) {
            RegionFrameScore fs;
            fs.frame = f.frame;
            fs.truth_id = f.regions[r].id;
            fs.change = f.regions[r].change;
            if (pick[r] >= 0) {
                fs.trace_id = found[pick[r]]->id;
                fs.match = matches[r * cols + pick[r]];
            }
            if (fs.match.corner_error_px) {
                ++s.with_corners;
                corner_sum += *fs.match.corner_error_px;
            }
            const int k = static_cast<int>(fs.match.cls);
            (k == 0 ? s.good : k == 1 ? s.ok : s.fail) += 1;
            ++s.by_change[fs.change][k];
            s.frames.push_back(std::move(fs));
        }
    }
    s.mean_corner_error_px = s.with_corners > 0 ? corner_sum / s.with_corners : 0;
    return s;
}

}  // namespace endotower::eval
