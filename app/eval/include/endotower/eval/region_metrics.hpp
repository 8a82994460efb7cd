// Region tracking classes GOOD / OK / FAIL (book ch. 6, fig. 6.20), made quantitative
// (docs/evaluation.md):
//   GOOD: "all content detected": coverage (area of truth covered by the trace
//         polygon / truth area) >= good_coverage (0.90), IoU >= good_iou (0.75) and,
//         when both polygons have the same vertex count, mean corner error <=
//         good_corner_fraction (0.10) x sqrt(truth area);
//   OK:   "partially matched": not GOOD, IoU >= ok_iou (0.25) or coverage >= 0.5
//         with the trace polygon at most 4x the truth area;
//   FAIL: not found (no trace region, state "lost", degenerate polygon) or neither.
// Trace regions are matched to truth regions per frame by greatest IoU (one to one).
// Corner error: mean distance between corresponding vertices (same index).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "endotower/eval/analysis_trace.hpp"
#include "endotower/eval/truth.hpp"

namespace endotower::eval {

enum class RegionClass { kGood = 0, kOk = 1, kFail = 2 };
const char* region_class_name(RegionClass c);

struct RegionRule {
    double good_coverage = 0.90, good_iou = 0.75, good_corner_fraction = 0.10;
    double ok_iou = 0.25, ok_coverage = 0.5, ok_max_area_ratio = 4.0;
};

double polygon_area(const std::vector<Point2>& p);  // absolute, shoelace
// Intersection area of two simple polygons: exact when either is convex (clipping);
// when neither is, by rasterising both (4 cells per px, at most 2048 cells a side;
// boundary cells count as inside, so it overestimates by about one cell per edge).
double polygon_intersection_area(const std::vector<Point2>& a, const std::vector<Point2>& b);

struct RegionMatch {
    double iou = 0, coverage = 0;
    std::optional<double> corner_error_px;
    RegionClass cls = RegionClass::kFail;
};
// trace == nullptr: not found.
RegionMatch classify_region(const std::vector<Point2>& truth, const std::vector<Point2>* trace,
                            const RegionRule& rule = {});

struct RegionFrameScore {
    std::int64_t frame = 0;
    int truth_id = 0, trace_id = -1;
    std::string change;
    RegionMatch match;
};
struct RegionScore {
    bool present = false;  // truth has regions and the trace a `regions` member
    int good = 0, ok = 0, fail = 0;
    int with_corners = 0;
    double mean_corner_error_px = 0;
    std::vector<RegionFrameScore> frames;
    std::map<std::string, std::array<int, 3>> by_change;  // change -> GOOD/OK/FAIL counts
};
RegionScore score_regions(const std::vector<TruthFrame>& truth,
                          const std::vector<AnalysisFrame>& trace, const RegionRule& rule = {});

}  // namespace endotower::eval
