// LikelihoodToolTracker: finds tools as elongated regions of a learned per-pixel tool
// probability (ToolLikelihood), entering from the border of the field of view.
//
// Per frame, on the frame reduced to `analysis_width` (320): the probability of every
// pixel from the model's table; nothing outside the lit field of view (9x9 mean grey
// above `surround_fraction` (0.35) x the frame's median grey and above `surround_level`
// (12), eroded by `surround_margin_px`); a 5x5 Gaussian; threshold at
// `threshold` (128 = even odds); a 3x3 opening; 8-connected regions. A region is a tool
// when at least `min_solid_fraction` (0.85) of its pixels are at even odds before the
// blur (glint speckle on wet tissue is not), its area is at least `min_area_fraction`
// of the frame, its length (principal axis, from the second moments) at least
// `min_elongation` x its width, and one end, not both, lies within
// `border_touch_fraction` x the frame width of the edge of the lit area or the image
// border (tools come in through the incision; a band with both ends there lies along
// the edge). Where one region meets the rim in two places (two
// tools touching or crossing) and not both are tracked, it is split by two lines
// fitted alternately to the pixels nearer each (k-lines), when the smaller entry is
// at least `min_entry_ratio` (0.2) of the larger. The
// larger regions win, up to `max_tools`.
// Per tool: the tip is the end away from the rim (mean of the region's pixels within
// 3 % of the length of that extreme); axis_deg points from the tip to the rim end, or
// (`tip_axis`) along the principal axis of the half of the region nearer the tip where
// that line runs through more of the region (a band along the rim joined to the shaft);
// width = area / length; the head (joint of shaft and jaws) is `head_widths` widths
// from the tip along the axis. Tracks (fig. 4.22/4.27/4.28): a constant-velocity
// Kalman filter per tool on the tip and the axis angle predicts each tool; regions go
// to tracks by the least summed distance of tip (in widths) and axis (in 20 degrees).
// A region shared by two tracked tools is split by their predicted shafts (entry to
// predicted tip, nearest segment), keeps the predicted axis (and no turning rate: it
// is not measured there), and does not look for a tool's end under the other's shaft
// or beyond its own width from its axis; such a
// measurement that jumps more than the gate (4 sigma, one to two widths) or turns by
// more than 20 degrees is the other tool's part, and the track reports its prediction
// at half confidence, up to `max_coast_frames`. A tool missing for `keep_frames`
// frames loses its id. Bars from the rim (`rim_bars`, RimBarSearch: a straight bar of
// likelihood above the tissue on both sides, coming in from the rim, found even below
// even odds): a region along a bar takes the bar's length as its support; a bar along no
// region, at least `bar_min_length_fraction` (0.3) x the width long and found in
// `bar_min_frames` (3) frames in a row, is a tool of its own (width: the bar's); where
// one is added, the candidates with the longest support (a region: its length; a part
// of a shared region: always) are the tools, not the largest (docs/tracking.md, "Bars
// from the rim"). Across a band (`bridge_widths`, 2): an elongated solid region off the
// rim whose axis, beyond one end, crosses at most that many widths below even odds and
// then runs on to the rim over at least two widths of points, 70 % of them tool-coloured,
// is a tool from its other end to the rim (a marker ring or a crossing instrument cut the
// shaft), in place of a region whose tip lies on that line. Results in the full frame's
// coordinates. Owns the model.
// configure() sizes every buffer; track() then allocates nothing (its image operations
// are MaskOps and BlockMean, OpenCV's bytes without OpenCV's per-call buffers), except
// that a frame width that is not an integer multiple of the analysis width (up to 15)
// is still reduced by cv::resize. `surround_margin_px` is at most 7.
#pragma once

#include <array>
#include <memory>

#include "endotower/vision/tool_likelihood.hpp"
#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

struct LikelihoodToolTrackerParams {
    int analysis_width = 320;
    int threshold = 128;
    int surround_level = 12;
    double surround_fraction = 0.35;
    int surround_margin_px = 3;
    double min_area_fraction = 0.004;
    double min_elongation = 2.0;
    double min_solid_fraction = 0.85;  // of a region, tool-coloured before the blur
    double border_touch_fraction = 0.06;
    double min_entry_ratio = 0.2;  // a second rim entry counts when >= this x the first
    double head_widths = 2.7;      // median on simulator training scenes (docs/tracking.md)
    int keep_frames = 5;
    int max_coast_frames = 25;  // a crossing at 3 cm/s takes about a second
    std::size_t max_tools = 2;
    bool rim_bars = true;                  // RimBarSearch (docs/tracking.md, "Bars from the rim")
    double bar_min_length_fraction = 0.3;  // of the width: a bar that is a tool on its own
    int bar_min_frames = 3;                // ... once found in this many frames in a row
    double bridge_widths = 2.0;            // a band across a shaft: at most this many widths
    bool tip_axis = true;                  // the axis near the tip where it fits the region better
};

class LikelihoodToolTracker final : public ToolTracker {
public:
    LikelihoodToolTracker(const ToolLikelihood& model, LikelihoodToolTrackerParams params = {});
    ~LikelihoodToolTracker() override;
    std::string_view name() const override { return "likelihood"; }
    void configure(const hal::FrameFormat& format) override;
    std::size_t track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) override;

private:
    struct Work;
    ToolLikelihood model_;
    LikelihoodToolTrackerParams params_;
    std::unique_ptr<Work> work_;
    int next_id_ = 0;
};

}  // namespace endotower::vision
