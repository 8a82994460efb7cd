// Truth derived from tool masks and homographies (derived_truth.hpp).
#include "endotower/eval/derived_truth.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace endotower::eval {

namespace {

double border_distance(const ToolMask& m, Point2 p) {
    return std::min({p.x, p.y, m.width - 1 - p.x, m.height - 1 - p.y});
}

}  // namespace

std::vector<TruthTool> tools_from_mask(const ToolMask& mask, double tip_band_px) {
    std::vector<TruthTool> tools;
    if (mask.width <= 0 || mask.height <= 0) return tools;
    // The mask keeps no labels; label again and pick each component by its box and area.
    cv::Mat on(mask.height, mask.width, CV_8U, const_cast<std::uint8_t*>(mask.on.data()));
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(on, labels, stats, centroids, 8, CV_32S);
    int id = 0;
    for (const MaskComponent& c : mask.components) {
        ++id;
        int label = -1;
        for (int i = 1; i < n && label < 0; ++i)
            if (stats.at<int>(i, cv::CC_STAT_AREA) == c.area && stats.at<int>(i, cv::CC_STAT_LEFT) == c.x0 &&
                stats.at<int>(i, cv::CC_STAT_TOP) == c.y0)
                label = i;
        if (label < 0) continue;
        const double a = c.axis_deg * M_PI / 180.0, ux = std::cos(a), uy = std::sin(a);
        double lo = 1e300, hi = -1e300;
        for (int y = c.y0; y <= c.y1; ++y)
            for (int x = c.x0; x <= c.x1; ++x)
                if (labels.at<int>(y, x) == label) {
                    const double s = (x - c.centroid.x) * ux + (y - c.centroid.y) * uy;
                    lo = std::min(lo, s);
                    hi = std::max(hi, s);
                }
        // Mean of the pixels within the band at each extreme.
        Point2 end_lo, end_hi;
        int n_lo = 0, n_hi = 0;
        for (int y = c.y0; y <= c.y1; ++y)
            for (int x = c.x0; x <= c.x1; ++x)
                if (labels.at<int>(y, x) == label) {
                    const double s = (x - c.centroid.x) * ux + (y - c.centroid.y) * uy;
                    if (s <= lo + tip_band_px) end_lo.x += x, end_lo.y += y, ++n_lo;
                    if (s >= hi - tip_band_px) end_hi.x += x, end_hi.y += y, ++n_hi;
                }
        end_lo = {end_lo.x / n_lo, end_lo.y / n_lo};
        end_hi = {end_hi.x / n_hi, end_hi.y / n_hi};
        const bool lo_is_tip = border_distance(mask, end_lo) > border_distance(mask, end_hi);
        const Point2 tip = lo_is_tip ? end_lo : end_hi, back = lo_is_tip ? end_hi : end_lo;
        TruthTool t;
        t.id = id;
        t.visible = true;
        t.tip_px = tip;
        t.axis_deg = std::atan2(back.y - tip.y, back.x - tip.x) * 180.0 / M_PI;
        const double length = std::max(1.0, hi - lo + 1.0);
        t.width_px = c.area / length;
        tools.push_back(t);
    }
    return tools;
}

bool region_truth_from_homography(const std::vector<std::vector<Point2>>& polygons,
                                  const Homography& h, std::int64_t first, std::int64_t last,
                                  std::vector<TruthFrame>& out, std::string& error) {
    out.clear();
    TruthFrame a, b;
    a.frame = first;
    b.frame = last;
    for (std::size_t i = 0; i < polygons.size(); ++i) {
        TruthRegion ra, rb;
        ra.id = rb.id = static_cast<int>(i) + 1;
        ra.polygon_px = polygons[i];
        rb.change = "homography";
        for (const Point2& p : polygons[i]) {
            const double w = h[6] * p.x + h[7] * p.y + h[8];
            if (std::abs(w) < 1e-12) {
                error = "the homography maps a vertex of region " + std::to_string(ra.id) +
                        " to infinity";
                return false;
            }
            rb.polygon_px.push_back(apply_homography(h, p));
        }
        a.regions.push_back(std::move(ra));
        b.regions.push_back(std::move(rb));
    }
    out.push_back(std::move(a));
    if (last != first) out.push_back(std::move(b));
    return true;
}

std::vector<std::vector<Point2>> first_trace_polygons(const std::vector<AnalysisFrame>& trace,
                                                      std::int64_t& frame) {
    std::vector<std::vector<Point2>> polys;
    for (const AnalysisFrame& f : trace) {
        if (f.regions.empty()) continue;
        frame = f.frame;
        std::vector<TraceRegion> rs = f.regions;
        std::sort(rs.begin(), rs.end(), [](const TraceRegion& x, const TraceRegion& y) { return x.id < y.id; });
        for (const TraceRegion& r : rs) polys.push_back(r.polygon_px);
        break;
    }
    return polys;
}

bool parse_polygon(const std::string& text, std::vector<Point2>& out, std::string& error) {
    out.clear();
    std::istringstream words(text);
    std::string w;
    while (words >> w) {
        const std::size_t comma = w.find(',');
        char* e1 = nullptr;
        char* e2 = nullptr;
        const std::string xs = w.substr(0, comma);
        const std::string ys = comma == std::string::npos ? "" : w.substr(comma + 1);
        const double x = std::strtod(xs.c_str(), &e1), y = std::strtod(ys.c_str(), &e2);
        if (comma == std::string::npos || xs.empty() || ys.empty() || *e1 != 0 || *e2 != 0 ||
            !std::isfinite(x) || !std::isfinite(y)) {
            error = "polygon vertex '" + w + "' must be x,y (two numbers)";
            return false;
        }
        out.push_back({x, y});
    }
    if (out.size() < 3) {
        error = "a polygon needs at least 3 vertices \"x1,y1 x2,y2 x3,y3\", got " + std::to_string(out.size());
        return false;
    }
    return true;
}

}  // namespace endotower::eval
