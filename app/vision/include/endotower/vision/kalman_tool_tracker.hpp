// KalmanToolTracker: the book's feature-based tracker (ch. 4): Canny + probabilistic
// Hough on the frame reduced to `analysis_width`, the two-bin edge labelling and
// merge (EdgePairing), the midline Kalman filter with slope/distance gating
// (MidlineKalman), loss after a few missed frames and automatic re-initialisation
// from the strongest edge pair, then the tip along the midline (TipExtractor).
// Variant `red_binarised` (fig. 4.12-4.13): Canny on the red channel binarised at
// `red_threshold` (tools are dark or grey, tissue is red) instead of grey.
// Edges within `surround_margin_px` (8) of the dark surround (grey <= `surround_level`,
// 20) are dropped: the field-of-view rim is never a tool edge.
// Up to `max_tools` (2) tools, one filter each (fig. 4.22): tracked filters take the
// segments their gates accept first, so a second tool keeps its own filter and id;
// a free filter starts on the strongest pair of what is left. Results are scaled
// back to full-resolution coordinates.
// Parameters: analysis_width 640; canny 40/120; hough threshold 50, minimum
// length 8 % of the analysis width, gap 10 px; plausible shaft width 6 px .. 30 %
// of the analysis width.
#pragma once

#include <array>
#include <memory>

#include "endotower/vision/midline_kalman.hpp"
#include "endotower/vision/tip_extractor.hpp"
#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

struct KalmanToolTrackerParams {
    int analysis_width = 640;
    bool red_binarised = false;
    int red_threshold = 110;
    double canny_low = 40, canny_high = 120;
    int hough_threshold = 50;
    double min_length_fraction = 0.08;
    double max_gap_px = 10;
    double min_width_px = 6;
    double max_width_fraction = 0.3;
    int surround_level = 20;
    int surround_margin_px = 8;
    double jaw_length_widths = 4.0;  // tip search beyond the edges' end, in shaft widths
    double used_distance_px = 6.0;   // segments this close to a tracked tool's edges are its own
    std::size_t max_tools = 2;
    MidlineKalmanParams kalman;
    TipExtractorParams tip{.last_strong_change = true, .use_saturation = true};
};

class KalmanToolTracker final : public ToolTracker {
public:
    explicit KalmanToolTracker(KalmanToolTrackerParams params = {});
    ~KalmanToolTracker() override;
    std::string_view name() const override { return params_.red_binarised ? "kalman_red" : "kalman"; }
    void configure(const hal::FrameFormat& format) override;
    std::size_t track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) override;

private:
    struct Work;
    struct Track {
        MidlineKalman kalman{MidlineKalmanParams{}};
        int id = -1;
    };
    void mark_used(const EdgePair& pair);
    void describe(const EdgePair& pair, int id, ToolEstimate& out);

    KalmanToolTrackerParams params_;
    std::unique_ptr<Work> work_;
    std::array<Track, kMaxTools> tracks_{};
    int next_id_ = 0;
};

}  // namespace endotower::vision
