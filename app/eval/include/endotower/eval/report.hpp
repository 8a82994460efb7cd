// The evaluation result, its pass/fail thresholds, and the report: a console summary,
// a markdown report (tables in the book's layouts) and PNG plots drawn with OpenCV.
//
// Thresholds (unset = not checked): min_success (0..1), max_mean_error_px,
// max_p95_error_px, max_mean_error_mm, max_false_positives (per frame),
// min_identity (0..1), min_gesture_rate (0..1, over trials), min_region_good
// (0..1, fraction of region-frames GOOD), max_corner_error_px. A threshold whose
// metric cannot be computed (e.g. no tip_mm, no gesture member) fails.
// Plots: tip_error.png (error over time with the success tolerance), success_by_factor.png
// (bars per factor level), gesture_confusion.png (row-normalised heat map with counts),
// regions.png (class and corner error over time); each only when it has data.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "endotower/eval/gesture_metrics.hpp"
#include "endotower/eval/region_metrics.hpp"
#include "endotower/eval/tool_metrics.hpp"

namespace endotower::eval {

struct EvalResult {
    std::string trace_path, truth_path;
    bool sznitman = false;  // truth is a sznitman_lap annotation file
    bool has_tools = false;  // the trace has a `tools` member on some line
    ToolScore tools;
    GestureScore gestures;
    RegionScore regions;
};

struct Thresholds {
    std::optional<double> min_success, max_mean_error_px, max_p95_error_px, max_mean_error_mm,
        max_false_positives, min_identity, min_gesture_rate, min_region_good,
        max_corner_error_px;
};

struct ThresholdCheck {
    std::string name;  // e.g. "success rate"
    std::string op;    // ">=" or "<="
    double limit = 0;
    std::optional<double> value;  // nullopt: the metric could not be computed
    bool pass = false;
};
std::vector<ThresholdCheck> check_thresholds(const EvalResult& r, const Thresholds& t);

std::string render_summary(const EvalResult& r, const std::vector<ThresholdCheck>& checks);
std::string render_markdown(const EvalResult& r, const std::vector<ThresholdCheck>& checks);
// (file name, PNG bytes) for each plot that has data.
std::vector<std::pair<std::string, std::string>> render_plots(const EvalResult& r);

}  // namespace endotower::eval
