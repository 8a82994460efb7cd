// Tool tracking scores (docs/evaluation.md).
//
// Per frame, the trace's tools are assigned one-to-one to the visible truth tools
// (or annotated tools) minimising the summed point distance (Hungarian method).
// Book rule (ch. 4): a truth tool-frame is a success when its assigned trace tool's
// tip is within width_factor (2) x width_px of the true tip AND its axis_deg within
// max_axis_deg (20) of the true axis (directions). Sznitman rule: head_px within
// head_scale_factor (0.5) x SCALE of the annotated head AND axis within 20 degrees as
// undirected lines. A tool-frame with no trace tool (or no trace line, or no `tools`
// member) fails. Trace tools left unassigned are false positives.
// Identity: for each truth id, the majority trace id over its successful pairs; the
// consistency is the fraction of successful pairs that carry that majority id.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "endotower/eval/analysis_trace.hpp"
#include "endotower/eval/annotations.hpp"
#include "endotower/eval/truth.hpp"

namespace endotower::eval {

struct ToolRule {
    double width_factor = 2.0;       // book rule: tip within 2 x tool width
    double head_scale_factor = 0.5;  // sznitman rule: head within 0.5 x SCALE
    double max_axis_deg = 20.0;
};

struct ToolPair {
    std::int64_t frame = 0;
    int truth_id = 0;
    int trace_id = -1;           // -1: no trace tool assigned
    double error_px = -1;        // tip (book) or head (sznitman) error; -1 when none
    double axis_error_deg = -1;  // -1 when none
    double tolerance_px = 0;     // 2 x width, or 0.5 x SCALE
    std::optional<double> error_mm;  // 3-D tip error where both tip_mm are known
    bool success = false;
};

struct LevelScore {
    std::string factor, level;
    int tool_frames = 0, matched = 0, successes = 0;
    double mean_error_px = 0;  // over matched pairs
};

struct ToolScore {
    std::string point = "tip";  // "tip" (book rule) or "head" (sznitman rule)
    int frames = 0, frames_without_trace = 0;
    int tool_frames = 0, matched = 0, successes = 0;
    double success_rate = 0;  // successes / tool_frames
    double mean_error_px = 0, p95_error_px = 0;  // over matched pairs
    int with_mm = 0;
    double mean_error_mm = 0, p95_error_mm = 0;
    int false_positives = 0;
    double false_positives_per_frame = 0;
    int identity_pairs = 0;  // successful pairs (when the truth has >= 2 tool ids)
    std::optional<double> identity_consistency;
    std::vector<ToolPair> pairs;  // one per truth tool-frame, in frame order
    std::vector<LevelScore> levels;  // per factor level (truth mode only)
};

ToolScore score_tools(const std::vector<TruthFrame>& truth,
                      const std::vector<AnalysisFrame>& trace, const ToolRule& rule = {});
// Trace frame i is annotation index first_index + i.
ToolScore score_sznitman(const SznitmanAnnotations& truth,
                         const std::vector<AnalysisFrame>& trace, int first_index,
                         const ToolRule& rule = {});

}  // namespace endotower::eval
