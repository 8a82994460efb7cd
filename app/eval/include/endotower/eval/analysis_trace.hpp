// The analysis members of a trace (docs/trace.md) that `eval` scores: `tools`,
// `gesture`, `regions`. Built on app::parse_trace_line (the base members are checked
// there); the analysis members are parsed from TraceRecord::extra.
//
// Members (absent = the stage showed no result on that frame):
//   "tools": [{"id", "tip_px": [x, y], "head_px": [x, y], "axis_deg", "confidence",
//              "tip_mm": [x, y, z] or null}]           (tip_mm may also be absent)
//   "gesture": {"label": name or null, "confidence", "held_ms", "fired"}
//   "regions": [{"id", "polygon_px": [[x, y], ...], "state": "tracked"|"lost", "inliers"}]
//   "markers": [{"center_px": [x, y], "diameter_px", "strips", "tip_mm": [x, y, z] or null}]
// Gesture labels: gesture_metrics.hpp kGestureClasses ("none" reads as null).
// Errors: "PATH:LINE: field 'tools[1].tip_px' must be [x, y] (two numbers)".
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "endotower/eval/truth.hpp"

namespace endotower::eval {

struct TraceTool {
    int id = 0;
    Point2 tip_px, head_px;
    double axis_deg = 0, confidence = 0;
    std::optional<Point3> tip_mm;
};

struct TraceGesture {
    std::optional<std::string> label;
    double confidence = 0, held_ms = 0;
    bool fired = false;
};

struct TraceRegion {
    int id = 0;
    std::vector<Point2> polygon_px;
    bool tracked = true;  // state "tracked" (false: "lost")
    int inliers = 0;
};

struct TraceMarker {
    Point2 center_px;
    double diameter_px = 0;
    int strips = 0;
    std::optional<Point3> tip_mm;
};

struct AnalysisFrame {
    std::int64_t frame = 0;
    bool has_tools = false, has_regions = false;
    std::vector<TraceTool> tools;
    std::optional<TraceGesture> gesture;
    std::vector<TraceRegion> regions;
    bool has_markers = false;
    std::vector<TraceMarker> markers;
};

bool parse_analysis_line(const std::string& line, AnalysisFrame& out, std::string& error);
// Errors are "PATH:LINE: what"; a frame index listed twice is an error.
bool read_analysis_trace(const std::string& path, std::vector<AnalysisFrame>& out,
                         std::string& error);

}  // namespace endotower::eval
