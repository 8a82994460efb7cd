// HybridToolTracker: the book's hybrid of the colour particle filter and the
// adaptive Gaussian mixture model (ch. 5, fig. 5.5-5.6), tracker name `hybrid`.
// The mixture model (Mog2ToolTracker, run every frame so its background stays
// current) finds the moving tool's rectangle; it initialises the particle filter
// (as ParticleToolTracker: 100 particles, HSV hue-saturation histograms, Bhattacharyya
// distance, eq. 5.5-5.12, and with `sorted_resampling` eq. 5.13-5.14) and re-
// initialises it whenever the filter is lost. Inside the filter's rectangle (grown
// by `roi_margin` 0.15 per side) the edges and tip are found as in ch. 4: Canny +
// probabilistic Hough on the frame reduced to `analysis_width` (640), EdgePairing,
// TipExtractor; where no plausible edge pair is found there, the rectangle's
// reference-coloured pixels give the region geometry instead. One tool;
// full-resolution coordinates.
#pragma once

#include <memory>

#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

struct HybridToolTrackerParams {
    int analysis_width = 640;
    int particles = 100;
    bool sorted_resampling = false;
    double roi_margin = 0.15;
    double canny_low = 40, canny_high = 120;
    int hough_threshold = 30;
    double min_length_fraction = 0.05;
    double min_width_px = 6, max_width_fraction = 0.3;
};

class HybridToolTracker final : public ToolTracker {
public:
    explicit HybridToolTracker(HybridToolTrackerParams params = {});
    ~HybridToolTracker() override;
    std::string_view name() const override { return "hybrid"; }
    void configure(const hal::FrameFormat& format) override;
    std::size_t track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) override;

private:
    struct Work;
    HybridToolTrackerParams params_;
    std::unique_ptr<Work> work_;
    int next_id_ = 0;
};

}  // namespace endotower::vision
