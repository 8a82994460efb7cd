#include "endotower/vision/mhi_tool_tracker.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/optflow/motempl.hpp>

#include "tracker_common.hpp"

namespace endotower::vision {

struct MhiToolTracker::Work {
    detail::AnalysisFrame frame;
    detail::RegionDescriber region;
    cv::Mat previous, silhouette, history, gradient_mask, orientation, moving, kernel;
    cv::Rect box;
    double timestamp = 0;
    bool primed = false;
};

MhiToolTracker::MhiToolTracker(MhiToolTrackerParams params)
    : params_(params), work_(std::make_unique<Work>()) {}

MhiToolTracker::~MhiToolTracker() = default;

void MhiToolTracker::configure(const hal::FrameFormat& format) {
    Work& w = *work_;
    w.frame.configure(format, params_.analysis_width, 4);
    w.region.configure(w.frame.small.cols, w.frame.small.rows);
    const cv::Size sz = w.frame.small.size();
    w.previous.create(sz, CV_8UC1);
    w.silhouette.create(sz, CV_8UC1);
    w.history = cv::Mat::zeros(sz, CV_32FC1);
    w.gradient_mask.create(sz, CV_8UC1);
    w.orientation.create(sz, CV_32FC1);
    w.moving.create(sz, CV_8UC1);
    w.kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7));
    w.box = {};
    w.timestamp = 0;
    w.primed = false;
}

void MhiToolTracker::last_box(int box[4]) const {
    const Work& w = *work_;
    const double inv = w.frame.scale > 0 ? 1.0 / w.frame.scale : 1.0;
    box[0] = static_cast<int>(w.box.x * inv);
    box[1] = static_cast<int>(w.box.y * inv);
    box[2] = static_cast<int>(w.box.width * inv);
    box[3] = static_cast<int>(w.box.height * inv);
}

std::size_t MhiToolTracker::track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) {
    Work& w = *work_;
    w.box = {};
    if (w.history.empty() || !w.frame.load(frame)) return 0;
    const cv::Mat& gray = w.frame.gray;
    w.timestamp += 1;
    if (!w.primed) {
        gray.copyTo(w.previous);
        w.primed = true;
        return 0;
    }
    cv::absdiff(gray, w.previous, w.silhouette);
    gray.copyTo(w.previous);
    cv::threshold(w.silhouette, w.silhouette, params_.diff_threshold, 1, cv::THRESH_BINARY);
    const double duration = params_.duration_frames;
    cv::motempl::updateMotionHistory(w.silhouette, w.history, w.timestamp, duration);
    // The recent history is the moving region (fig. 4.3-4.4).
    cv::threshold(w.history, w.orientation, w.timestamp - duration, 255, cv::THRESH_BINARY);
    w.orientation.convertTo(w.moving, CV_8U);
    cv::morphologyEx(w.moving, w.moving, cv::MORPH_CLOSE, w.kernel);
    cv::bitwise_and(w.moving, w.frame.lit, w.moving);
    if (cv::countNonZero(w.moving) == 0) return 0;
    w.box = cv::boundingRect(w.moving);
    // Fig. 4.5-4.6: the direction of motion from the history's gradient.
    cv::motempl::calcMotionGradient(w.history, w.gradient_mask, w.orientation, 1, duration, 3);
    const double motion_deg = cv::motempl::calcGlobalOrientation(w.orientation, w.gradient_mask,
                                                                 w.history, w.timestamp, duration);
    detail::RegionShapeParams shape;
    shape.tip_direction_deg = motion_deg;
    if (!w.region.describe(w.frame, w.moving, w.box, shape, 0, out[0])) return 0;
    return 1;
}

}  // namespace endotower::vision
