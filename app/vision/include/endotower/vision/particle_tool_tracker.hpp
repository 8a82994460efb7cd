// ParticleToolTracker: the book's colour particle filter (ch. 5, eq. 5.5-5.12),
// tracker names `particle` and, with the weight-sorted resampling of eq. 5.13-5.14,
// `particle_sorted`. On the frame reduced to `analysis_width` (320): a rectangle
// [xc, yc, xc', yc', w, h, w', h'] (eq. 5.9) followed by `particles` (100) particles
// weighted by the Bhattacharyya distance of their HSV hue-saturation histograms
// (8 x 8 bins) to the reference, w = exp(-lambda d^2) (lambda 100), resampled when
// N_eff < N/2. As the book does (eq. 5.9's text), the reference rectangle comes from
// the motion history image (MhiToolTracker's moving region), and again whenever the
// filter is lost (the estimate's distance to the reference above 0.6).
// The tool: the pixels of low saturation whose hue-saturation bin is twice as likely
// in the reference as in the whole frame at initialisation, in the lit field of view,
// inside the rectangle grown by half its size per side (along a shaft the histogram
// does not change with the rectangle's length, so it often stops short of the tip);
// their largest 8-connected component gives axis, tip, head and edges
// (RegionDescriber). One tool; full-resolution coordinates. Deterministic (fixed seed).
#pragma once

#include <memory>

#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

struct ParticleToolTrackerParams {
    int analysis_width = 320;
    int particles = 100;
    double lambda = 100;
    bool sorted_resampling = false;  // eq. 5.13-5.14
};

class ParticleToolTracker final : public ToolTracker {
public:
    explicit ParticleToolTracker(ParticleToolTrackerParams params = {});
    ~ParticleToolTracker() override;
    std::string_view name() const override {
        return params_.sorted_resampling ? "particle_sorted" : "particle";
    }
    void configure(const hal::FrameFormat& format) override;
    std::size_t track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) override;

private:
    struct Work;
    ParticleToolTrackerParams params_;
    std::unique_ptr<Work> work_;
    int next_id_ = 0;
};

}  // namespace endotower::vision
