#include "endotower/vision/mog2_tool_tracker.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/background_segm.hpp>

#include "tracker_common.hpp"

namespace endotower::vision {

struct Mog2ToolTracker::Work {
    detail::AnalysisFrame frame;
    detail::RegionDescriber region;
    cv::Ptr<cv::BackgroundSubtractorMOG2> model;
    cv::Mat foreground, open_kernel, close_kernel;
    long frames = 0;
    cv::Rect box;
};

Mog2ToolTracker::Mog2ToolTracker(Mog2ToolTrackerParams params)
    : params_(params), work_(std::make_unique<Work>()) {}

Mog2ToolTracker::~Mog2ToolTracker() = default;

void Mog2ToolTracker::configure(const hal::FrameFormat& format) {
    Work& w = *work_;
    w.frame.configure(format, params_.analysis_width, 4);
    w.region.configure(w.frame.small.cols, w.frame.small.rows);
    w.model = cv::createBackgroundSubtractorMOG2(params_.history, params_.var_threshold, true);
    w.foreground.create(w.frame.small.size(), CV_8UC1);
    w.frames = 0;
    w.open_kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
    w.close_kernel =
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(params_.close_px, params_.close_px));
}

std::size_t Mog2ToolTracker::track(const hal::Frame& frame,
                                   std::span<ToolEstimate, kMaxTools> out) {
    Work& w = *work_;
    if (!w.model || !w.frame.load(frame)) return 0;
    // The first frame is the background; then a fixed rate of 1/history (OpenCV's
    // default rate is 1/frames for the first `history` frames, which absorbs a tool
    // into the background within a few frames of a clip's start).
    w.model->apply(w.frame.small, w.foreground, w.frames++ == 0 ? 1.0 : 1.0 / params_.history);
    // Shadows (127) are not the tool: fig. 4.18d.
    cv::threshold(w.foreground, w.foreground, 200, 255, cv::THRESH_BINARY);
    cv::morphologyEx(w.foreground, w.foreground, cv::MORPH_OPEN, w.open_kernel);
    cv::morphologyEx(w.foreground, w.foreground, cv::MORPH_CLOSE, w.close_kernel);
    cv::bitwise_and(w.foreground, w.frame.lit, w.foreground);
    const cv::Rect all(0, 0, w.foreground.cols, w.foreground.rows);
    w.box = {};
    if (!w.region.describe(w.frame, w.foreground, all, {}, 0, out[0])) return 0;
    w.box = cv::boundingRect(w.foreground);
    return 1;
}

void Mog2ToolTracker::last_box(int box[4]) const {
    const Work& w = *work_;
    const double inv = w.frame.scale > 0 ? 1.0 / w.frame.scale : 1.0;
    box[0] = static_cast<int>(w.box.x * inv);
    box[1] = static_cast<int>(w.box.y * inv);
    box[2] = static_cast<int>(w.box.width * inv);
    box[3] = static_cast<int>(w.box.height * inv);
}

}  // namespace endotower::vision
