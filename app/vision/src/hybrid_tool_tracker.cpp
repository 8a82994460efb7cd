#include "endotower/vision/hybrid_tool_tracker.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "colour_particle_filter.hpp"
#include "endotower/vision/mog2_tool_tracker.hpp"
#include "tracker_common.hpp"

namespace endotower::vision {

struct HybridToolTracker::Work {
    explicit Work(const HybridToolTrackerParams& p)
        : filter({.particles = p.particles, .sorted_resampling = p.sorted_resampling}) {}
    detail::AnalysisFrame frame;
    detail::RegionDescriber region;
    detail::ColourParticleFilter filter;
    Mog2ToolTracker mixture;
    cv::Mat blurred, edges, mask;
    std::vector<cv::Vec4i> lines;
    std::vector<Segment> segments;
    int id = -1;
};

HybridToolTracker::HybridToolTracker(HybridToolTrackerParams params)
    : params_(params), work_(std::make_unique<Work>(params)) {}

HybridToolTracker::~HybridToolTracker() = default;

void HybridToolTracker::configure(const hal::FrameFormat& format) {
    Work& w = *work_;
    w.frame.configure(format, params_.analysis_width, 8);
    const cv::Size sz = w.frame.small.size();
    w.region.configure(sz.width, sz.height);
    w.filter.configure(sz);
    w.mixture.configure(format);
    w.blurred.create(sz, CV_8UC1);
    w.edges.create(sz, CV_8UC1);
    w.mask.create(sz, CV_8UC1);
    w.lines.reserve(4096);
    w.segments.reserve(4096);
    w.id = -1;
}

std::size_t HybridToolTracker::track(const hal::Frame& frame,
                                     std::span<ToolEstimate, kMaxTools> out) {
    Work& w = *work_;
    if (!w.frame.load(frame)) return 0;
    w.filter.load(w.frame.small);
    const std::size_t moving = w.mixture.track(frame, out);
    const double s = w.frame.scale;
    const cv::Rect all(0, 0, w.frame.small.cols, w.frame.small.rows);
    cv::Rect box;
    if (!w.filter.initialised() || w.filter.lost()) {
        // Fig. 5.5: the mixture model (re-)initialises the particle filter.
        if (moving == 0) return 0;
        int b[4];
        w.mixture.last_box(b);
        box = cv::Rect(static_cast<int>(b[0] * s), static_cast<int>(b[1] * s),
                       static_cast<int>(b[2] * s), static_cast<int>(b[3] * s)) &
              all;
        if (box.area() <= 0) return 0;
        w.filter.init(box);
        w.id = next_id_++;
    } else {
        box = w.filter.step() & all;
        if (w.filter.lost() || box.area() <= 0) return 0;
    }
    // Edges and tip inside the filter's rectangle (fig. 5.6).
    const int mx = static_cast<int>(params_.roi_margin * box.width),
              my = static_cast<int>(params_.roi_margin * box.height);
    const cv::Rect roi =
        cv::Rect(box.x - mx, box.y - my, box.width + 2 * mx, box.height + 2 * my) & all;
    cv::GaussianBlur(w.frame.gray(roi), w.blurred(roi), cv::Size(5, 5), 1.5);
    w.edges.setTo(0);
    cv::Canny(w.blurred(roi), w.edges(roi), params_.canny_low, params_.canny_high);
    cv::bitwise_and(w.edges(roi), w.frame.lit(roi), w.edges(roi));
    w.lines.clear();
    cv::HoughLinesP(w.edges(roi), w.lines, 1, CV_PI / 360, params_.hough_threshold,
                    params_.min_length_fraction * w.frame.small.cols, 10);
    w.segments.clear();
    for (const cv::Vec4i& l : w.lines)
        w.segments.push_back({{double(l[0] + roi.x), double(l[1] + roi.y)},
                              {double(l[2] + roi.x), double(l[3] + roi.y)}});
    std::sort(w.segments.begin(), w.segments.end(),
              [](const Segment& a, const Segment& b) { return a.length() > b.length(); });
    const EdgePair pair = pair_edges(w.segments);
    if (pair.found && pair.width_px >= params_.min_width_px &&
        pair.width_px <= params_.max_width_fraction * w.frame.small.cols) {
        detail::describe_pair(w.frame, pair, w.id, 4.0,
                              {.last_strong_change = true, .use_saturation = true}, out[0]);
        return 1;
    }
    // No edge pair: the reference-coloured pixels of the rectangle.
    w.mask.setTo(0);
    for (int y = box.y; y < box.y + box.height; ++y) {
        std::uint8_t* row = w.mask.ptr<std::uint8_t>(y);
        const std::uint8_t* lit = w.frame.lit.ptr<std::uint8_t>(y);
        for (int x = box.x; x < box.x + box.width; ++x)
            row[x] = lit[x] && w.filter.is_target_colour(y, x) ? 255 : 0;
    }
    return w.region.describe(w.frame, w.mask, box, {}, w.id, out[0]) ? 1 : 0;
}

}  // namespace endotower::vision
