#include "endotower/vision/particle_tool_tracker.hpp"

#include <opencv2/imgproc.hpp>

#include "colour_particle_filter.hpp"
#include "endotower/vision/mhi_tool_tracker.hpp"
#include "tracker_common.hpp"

namespace endotower::vision {

struct ParticleToolTracker::Work {
    explicit Work(const ParticleToolTrackerParams& p)
        : filter({.particles = p.particles,
                  .lambda = p.lambda,
                  .sorted_resampling = p.sorted_resampling}),
          mhi({.analysis_width = p.analysis_width}) {}
    detail::AnalysisFrame frame;
    detail::RegionDescriber region;
    detail::ColourParticleFilter filter;
    MhiToolTracker mhi;
    cv::Mat mask;
    int id = -1;
};

ParticleToolTracker::ParticleToolTracker(ParticleToolTrackerParams params)
    : params_(params), work_(std::make_unique<Work>(params)) {}

ParticleToolTracker::~ParticleToolTracker() = default;

void ParticleToolTracker::configure(const hal::FrameFormat& format) {
    Work& w = *work_;
    w.frame.configure(format, params_.analysis_width, 4);
    w.region.configure(w.frame.small.cols, w.frame.small.rows);
    w.filter.configure(w.frame.small.size());
    w.mhi.configure(format);
    w.mask.create(w.frame.small.size(), CV_8UC1);
    w.id = -1;
}

std::size_t ParticleToolTracker::track(const hal::Frame& frame,
                                       std::span<ToolEstimate, kMaxTools> out) {
    Work& w = *work_;
    if (!w.frame.load(frame)) return 0;
    w.filter.load(w.frame.small);
    // The motion history runs every frame so that it is current when it is needed.
    const std::size_t moving = w.mhi.track(frame, out);
    cv::Rect box;
    if (!w.filter.initialised() || w.filter.lost()) {
        if (moving == 0) return 0;
        int b[4];
        w.mhi.last_box(b);
        const double s = w.frame.scale;
        box = cv::Rect(static_cast<int>(b[0] * s), static_cast<int>(b[1] * s),
                       static_cast<int>(b[2] * s), static_cast<int>(b[3] * s));
        if (box.area() <= 0) return 0;
        w.filter.init(box);
        w.id = next_id_++;
    } else {
        box = w.filter.step();
        if (w.filter.lost()) return 0;
    }
    // The tool's pixels: the reference's colours inside the rectangle grown by half
    // its size per side. Along a shaft the histogram does not change with the
    // rectangle's length, so the filter's rectangle often stops short of the tip.
    w.mask.setTo(0);
    box = cv::Rect(box.x - box.width / 2, box.y - box.height / 2, box.width * 2, box.height * 2) &
          cv::Rect(0, 0, w.mask.cols, w.mask.rows);
    for (int y = box.y; y < box.y + box.height; ++y) {
        std::uint8_t* row = w.mask.ptr<std::uint8_t>(y);
        const std::uint8_t* lit = w.frame.lit.ptr<std::uint8_t>(y);
        for (int x = box.x; x < box.x + box.width; ++x)
            row[x] = lit[x] && w.filter.is_target_colour(y, x) ? 255 : 0;
    }
    detail::RegionShapeParams shape;
    shape.largest_component = true;
    return w.region.describe(w.frame, w.mask, box, shape, w.id, out[0]) ? 1 : 0;
}

}  // namespace endotower::vision
