#include "endotower/vision/midline_kalman.hpp"

#include <cmath>
#include <opencv2/video/tracking.hpp>

namespace endotower::vision {

struct MidlineKalman::Filter {
    cv::KalmanFilter kf{4, 2, 0, CV_64F};
    cv::Mat measurement = cv::Mat::zeros(2, 1, CV_64F);
};

MidlineKalman::MidlineKalman(MidlineKalmanParams params)
    : params_(params), filter_(std::make_unique<Filter>()) {
    cv::KalmanFilter& kf = filter_->kf;
    // Eq. 4.9: m += m', b += b'.
    kf.transitionMatrix = (cv::Mat_<double>(4, 4) << 1, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1, 0, 0, 0, 0, 1);
    // Eq. 4.10: [m, b] measured.
    kf.measurementMatrix = (cv::Mat_<double>(2, 4) << 1, 0, 0, 0, 0, 1, 0, 0);
    kf.processNoiseCov = cv::Mat::eye(4, 4, CV_64F) * params_.process_noise;
    kf.measurementNoiseCov = cv::Mat::ones(2, 2, CV_64F) * params_.measurement_noise;
}

MidlineKalman::~MidlineKalman() = default;
MidlineKalman::MidlineKalman(MidlineKalman&&) noexcept = default;
MidlineKalman& MidlineKalman::operator=(MidlineKalman&&) noexcept = default;

void MidlineKalman::set_state(const SlopeLine& l, double dm, double db) {
    cv::KalmanFilter& kf = filter_->kf;
    kf.statePost.at<double>(0) = l.m;
    kf.statePost.at<double>(1) = l.b;
    kf.statePost.at<double>(2) = dm;
    kf.statePost.at<double>(3) = db;
    kf.errorCovPost = cv::Mat::eye(4, 4, CV_64F);
    line_ = l;
}

void MidlineKalman::init(const Segment& midline) {
    set_state(SlopeLine::through(midline), 0, 0);
    initialised_ = true;
    missed_ = 0;
}

SlopeLine MidlineKalman::predict() {
    cv::KalmanFilter& kf = filter_->kf;
    const cv::Mat& x = kf.predict();
    line_ = {x.at<double>(0), x.at<double>(1), line_.x_major};
    if (std::abs(line_.m) > params_.swap_slope) {
        // Steeper than the current axis handles well: continue in the other one.
        const SlopeLine s = line_.swapped();
        set_state(s, 0, 0);
        kf.statePre = kf.statePost.clone();
        kf.errorCovPre = kf.errorCovPost.clone();
    }
    return line_;
}

SlopeLine MidlineKalman::correct(const Segment& measured) {
    cv::KalmanFilter& kf = filter_->kf;
    const SlopeLine z = SlopeLine::through(measured, line_.x_major);
    filter_->measurement.at<double>(0) = z.m;
    filter_->measurement.at<double>(1) = z.b;
    const cv::Mat& x = kf.correct(filter_->measurement);
    line_ = {x.at<double>(0), x.at<double>(1), line_.x_major};
    missed_ = 0;
    return line_;
}

bool MidlineKalman::gate(const Segment& edge) const {
    const SlopeLine e = SlopeLine::through(edge, line_.x_major);
    if (std::abs(e.m - line_.m) >= params_.gate_slope) return false;
    return std::max(line_.distance(edge.a), line_.distance(edge.b)) < params_.gate_distance_px;
}

}  // namespace endotower::vision
