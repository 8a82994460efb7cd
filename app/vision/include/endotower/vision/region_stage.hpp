// RegionStage: runs a RegionTracker on the analysis path, marks the regions it is
// given at their frames, draws the anchored overlay and writes the trace member
//   "regions": [{"id", "polygon_px": [[x, y], ...], "state": "tracked" | "lost",
//                "inliers"}]
// every frame once a region is marked (polygon_px: the last known outline while lost),
// in the input's own pixel coordinates. The overlay (the outline, its corners and a
// marker at its centre) is drawn only while the region is tracked: hidden, never
// misplaced, when it is lost; only for regions whose overlay is kMarkers (an image or
// an object is AnchoredOverlayStage's, which reads estimates()). Borrows the tracker.
//
// Marking with the tool (enable_tool_marking): a long press of the handle starts an
// outline (RegionMarker: vertices by button press or a still tip, closed by returning
// to the first vertex or a long press); the closed polygon becomes a new region on
// that frame. The outline so far, and the dwell progress at the tip, are drawn; the
// trace member every frame while enabled:
//   "region_marking": {"marking", "vertices": [[x, y], ...], "event": "started" |
//                      "vertex" | "closed" | "cancelled" | "refused" | null}
// ("refused": the closed polygon could not be tracked, e.g. too few features).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/vision/anchored_overlay.hpp"
#include "endotower/vision/region_marker.hpp"
#include "endotower/vision/region_tracker.hpp"

namespace endotower::vision {

struct RegionMark {
    std::int64_t frame = 0;  // source sequence number (0 = the first frame)
    int id = 0;
    std::vector<Point2> polygon;  // in that frame's pixels
    RegionOverlay overlay;        // what is anchored to it
};

class RegionStage final : public app::AnalysisStage {
public:
    explicit RegionStage(RegionTracker& tracker) : tracker_(tracker) {}
    // Before the run: a region to mark at the first analysed frame >= mark.frame.
    void schedule(RegionMark mark);
    // After the run: marks that failed ("frame N: region 2: ..."), one per line.
    const std::vector<std::string>& errors() const { return errors_; }
    // `tip` fills the tool tip of this frame (frame pixels), false when there is no tool;
    // called once per frame on the analysis thread after the tracker ran, must not allocate.
    void enable_tool_marking(const RegionMarkerParams& params, std::function<bool(Point2&)> tip);
    // The overlay of regions marked with the tool (default: markers).
    void set_tool_overlay(RegionOverlay overlay) { tool_overlay_ = std::move(overlay); }
    // Region `id`'s overlay (as scheduled; the tool's for regions marked with it).
    const RegionOverlay& overlay(int id) const;
    // This frame's estimates (after process(); empty before the first mark).
    std::span<const RegionEstimate> estimates() const { return {estimates_.data(), count_}; }

    std::string_view name() const override { return "regions"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;

private:
    RegionTracker& tracker_;
    std::vector<RegionMark> pending_;  // sorted by frame
    std::size_t next_ = 0;
    std::vector<std::string> errors_;
    std::array<RegionEstimate, RegionTracker::kMaxRegions> estimates_{};
    std::size_t count_ = 0;
    std::vector<std::pair<int, RegionOverlay>> overlays_;  // by id, from the marks
    RegionOverlay tool_overlay_;
    int thickness_ = 2;
    void mark_with_tool(app::AnalysisContext& ctx);
    std::function<bool(Point2&)> tip_;
    RegionMarker marker_;
    int next_id_ = 0;
};

}  // namespace endotower::vision
