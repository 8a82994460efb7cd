// Strip-marker scores (book ch. 3, tables 3.1/3.2): the trace's "markers" against the
// truth's per-tool "markers" (docs/truth.md).
//
// Per frame and truth tool with a visible strip, the target is its visible strip
// nearest the tip (lowest index). The trace marker nearest (px) to the target is
// matched when it lies within half its own diameter M of it; it picked the right
// strip when no other strip of that tool is nearer. Over matched markers with
// "tip_mm": the mean relative errors |est - truth| / |truth| of depth (z), and of x
// and y where the truth's coordinate is not within 0.5 mm of 0 (a percentage of 0 is
// undefined; the book's tables 3.1/3.2 use the same test points).
// `points` groups the estimates by test point (truth mm rounded) for the table.
#pragma once

#include <string>
#include <vector>

#include "endotower/eval/analysis_trace.hpp"
#include "endotower/eval/truth.hpp"

namespace endotower::eval {

struct MarkerPoint {
    Point3 truth;  // rounded to whole mm
    std::vector<Point3> estimates;
};

struct MarkerScore {
    int targets = 0, matched = 0, located = 0, right_strip = 0;
    double depth_error = 0, x_error = 0, y_error = 0;  // mean relative errors (0..1)
    int depth_n = 0, x_n = 0, y_n = 0;
    std::vector<MarkerPoint> points;
    bool empty() const { return targets == 0; }
};

MarkerScore score_markers(const std::vector<TruthFrame>& truth,
                          const std::vector<AnalysisFrame>& trace);
// The summary lines and the table in table 3.2's layout (rows: distance; columns:
// test points (x, y); cells: the mean estimate "(x, y) z").
std::string render_marker_summary(const MarkerScore& s);

}  // namespace endotower::eval
