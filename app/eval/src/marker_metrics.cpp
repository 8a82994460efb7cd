#include "endotower/eval/marker_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>
#include <utility>

namespace endotower::eval {

namespace {

double dist(Point2 a, Point2 b) {
    return std::hypot(a.x - b.x, a.y - b.y);
}

}  // namespace

MarkerScore score_markers(const std::vector<TruthFrame>& truth,
                          const std::vector<AnalysisFrame>& trace) {
    MarkerScore s;
    std::map<std::int64_t, const AnalysisFrame*> by_frame;
    for (const AnalysisFrame& f : trace) by_frame[f.frame] = &f;
    for (const TruthFrame& g : truth) {
        const auto it = by_frame.find(g.frame);
        for (const TruthTool& tool : g.tools) {
            const TruthMarker* target = nullptr;
            for (const TruthMarker& m : tool.markers)
                if (m.visible && (!target || m.strip < target->strip)) target = &m;
            if (!target) continue;
            ++s.targets;
            if (it == by_frame.end()) continue;
            const TraceMarker* best = nullptr;
            for (const TraceMarker& m : it->second->markers)
                if (!best ||
                    dist(m.center_px, target->center_px) < dist(best->center_px, target->center_px))
                    best = &m;
            if (!best || dist(best->center_px, target->center_px) > 0.5 * best->diameter_px)
                continue;
            ++s.matched;
            bool right = true;
            for (const TruthMarker& m : tool.markers)
                if (&m != target &&
                    dist(m.center_px, best->center_px) < dist(target->center_px, best->center_px))
                    right = false;
            s.right_strip += right ? 1 : 0;
            if (!best->tip_mm) continue;
            ++s.located;
            const Point3 t = target->center_mm, e = *best->tip_mm;
            s.depth_error += std::abs(e.z - t.z) / t.z, ++s.depth_n;
            if (std::abs(t.x) > 0.5) s.x_error += std::abs(e.x - t.x) / std::abs(t.x), ++s.x_n;
            if (std::abs(t.y) > 0.5) s.y_error += std::abs(e.y - t.y) / std::abs(t.y), ++s.y_n;
            const Point3 key{std::round(t.x) + 0.0, std::round(t.y) + 0.0, std::round(t.z) + 0.0};
            auto p = std::find_if(s.points.begin(), s.points.end(), [&](const MarkerPoint& q) {
                return q.truth.x == key.x && q.truth.y == key.y && q.truth.z == key.z;
            });
            if (p == s.points.end()) p = s.points.insert(s.points.end(), MarkerPoint{key, {}});
            p->estimates.push_back(e);
        }
    }
    if (s.depth_n) s.depth_error /= s.depth_n;
    if (s.x_n) s.x_error /= s.x_n;
    if (s.y_n) s.y_error /= s.y_n;
    return s;
}

std::string render_marker_summary(const MarkerScore& s) {
    std::string out;
    char line[256];
    std::snprintf(
        line, sizeof line,
        "markers (the visible strip nearest the tip, book tables 3.1/3.2): %d targets, %d found, "
        "%d on the right strip, %d located in mm\n",
        s.targets, s.matched, s.right_strip, s.located);
    out += line;
    if (s.located == 0) return out;
    std::snprintf(line, sizeof line,
                  "  mean error: depth %.2f %% (%d), x %.2f %% (%d), y %.2f %% (%d)\n",
                  100 * s.depth_error, s.depth_n, 100 * s.x_error, s.x_n, 100 * s.y_error, s.y_n);
    out += line;
    // Table 3.2's layout: one row per distance, one column per test point.
    std::vector<std::pair<double, double>> cols;
    std::vector<double> rows;
    for (const MarkerPoint& p : s.points) {
        if (std::find(cols.begin(), cols.end(), std::make_pair(p.truth.x, p.truth.y)) == cols.end())
            cols.emplace_back(p.truth.x, p.truth.y);
        if (std::find(rows.begin(), rows.end(), p.truth.z) == rows.end()) rows.push_back(p.truth.z);
    }
    std::sort(rows.begin(), rows.end());
    // The book's column order: the four diagonal points, then the four on the axes.
    const auto key = [](const std::pair<double, double>& c) {
        return std::make_tuple(c.first == 0 || c.second == 0, c.second == 0, -c.second, -c.first);
    };
    std::sort(cols.begin(), cols.end(),
              [&](const auto& a, const auto& b) { return key(a) < key(b); });
    out += "  | distance |";
    for (const auto& c : cols) {
        std::snprintf(line, sizeof line, " (%g, %g) |", c.first, c.second);
        out += line;
    }
    out += "\n  |---|";
    for (std::size_t i = 0; i < cols.size(); ++i) out += "---|";
    out += "\n";
    for (double z : rows) {
        std::snprintf(line, sizeof line, "  | %g mm |", z);
        out += line;
        for (const auto& c : cols) {
            const auto p =
                std::find_if(s.points.begin(), s.points.end(), [&](const MarkerPoint& q) {
                    return q.truth.x == c.first && q.truth.y == c.second && q.truth.z == z;
                });
            if (p == s.points.end() || p->estimates.empty()) {
                out += " |";
                continue;
            }
            Point3 m;
            for (const Point3& e : p->estimates) m.x += e.x, m.y += e.y, m.z += e.z;
            const double n = static_cast<double>(p->estimates.size());
            std::snprintf(line, sizeof line, " (%.1f, %.1f) %.1f |", m.x / n, m.y / n, m.z / n);
            out += line;
        }
        out += "\n";
    }
    return out;
}

}  // namespace endotower::eval
