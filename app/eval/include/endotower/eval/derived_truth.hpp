// Ground truth derived from the real annotation formats that are not per-frame tool
// records: binary tool masks and image-pair homographies (../shared/data). The result
// is ordinary TruthFrame data, so the book's rules in tool_metrics / region_metrics
// score it exactly as they score the simulator's truth.
//
// Tools from a mask: each component of the mask (read_tool_mask) is one instrument.
// Its principal axis gives the direction; the two extremes along the axis are the
// ends. The tool enters the picture from the border, so the end nearer the image
// border is the shaft side and the other is the tip (the mean of the component's
// pixels within `tip_band_px` of that extreme, so one stray pixel cannot move it).
// width_px = area / length along the axis (the mean apparent width);
// axis_deg points from the tip towards the shaft end, as in truth.jsonl.
//
// Regions from a homography H that maps the first frame's pixels to the last
// frame's: the marked polygon at the first frame is the truth there; H(polygon) is
// the truth at the last frame. Frames in between have no truth (not scored).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "endotower/eval/analysis_trace.hpp"
#include "endotower/eval/annotations.hpp"
#include "endotower/eval/truth.hpp"

namespace endotower::eval {

// The tools of one mask; ids 1, 2, ... in the order of mask.components (largest first).
std::vector<TruthTool> tools_from_mask(const ToolMask& mask, double tip_band_px = 3.0);

// Truth frames for a region scored against a homography. `polygons`: the marked
// regions at the first frame, one per region id (id = index + 1). first/last: trace
// frame numbers. Errors when a mapped vertex goes to infinity (behind the camera).
bool region_truth_from_homography(const std::vector<std::vector<Point2>>& polygons,
                                  const Homography& first_to_last, std::int64_t first,
                                  std::int64_t last, std::vector<TruthFrame>& out,
                                  std::string& error);

// The regions a trace reports at its first frame with regions (what was marked), in
// trace-id order; empty when the trace has none.
std::vector<std::vector<Point2>> first_trace_polygons(const std::vector<AnalysisFrame>& trace,
                                                      std::int64_t& frame);

// "x1,y1 x2,y2 x3,y3 ..." (at least 3 points) as used by `sim --region`.
bool parse_polygon(const std::string& text, std::vector<Point2>& out, std::string& error);

}  // namespace endotower::eval
