#include "colour_particle_filter.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "endotower/vision/particle_resampling.hpp"

namespace endotower::vision::detail {

ColourParticleFilter::ColourParticleFilter(ColourParticleFilterParams params)
    : params_(params), rng_(params.seed) {}

void ColourParticleFilter::configure(cv::Size image) {
    size_ = image;
    hsv_.create(image, CV_8UC3);
    bins_.create(image, CV_8UC1);
    const auto n = static_cast<std::size_t>(params_.particles);
    particles_.assign(n, {});
    resampled_.assign(n, {});
    weights_.assign(n, 0);
    order_.assign(n, 0);
    source_.assign(n, 0);
    const auto m =
        static_cast<std::size_t>(params_.hue_bins) * static_cast<std::size_t>(params_.sat_bins);
    reference_.assign(m, 0);
    frame_hist_.assign(m, 0);
    scratch_.assign(m, 0);
    target_bin_.assign(m, 0);
    initialised_ = false;
    rng_ = cv::RNG(params_.seed);
}

void ColourParticleFilter::load(const cv::Mat& bgr) {
    cv::cvtColor(bgr, hsv_, cv::COLOR_BGR2HSV);  // H 0..179, S 0..255
    for (int y = 0; y < hsv_.rows; ++y) {
        const cv::Vec3b* in = hsv_.ptr<cv::Vec3b>(y);
        std::uint8_t* out = bins_.ptr<std::uint8_t>(y);
        for (int x = 0; x < hsv_.cols; ++x)
            out[x] =
                static_cast<std::uint8_t>((in[x][0] * params_.hue_bins / 180) * params_.sat_bins +
                                          in[x][1] * params_.sat_bins / 256);
    }
}

void ColourParticleFilter::histogram(cv::Rect box, std::vector<float>& h) const {
    std::fill(h.begin(), h.end(), 0.0f);
    box &= cv::Rect(0, 0, size_.width, size_.height);
    float n = 0;
    for (int y = box.y; y < box.y + box.height; y += 2) {
        const std::uint8_t* row = bins_.ptr<std::uint8_t>(y);
        for (int x = box.x; x < box.x + box.width; x += 2) {
            h[row[x]] += 1;
            n += 1;
        }
    }
    if (n > 0)
        for (float& v : h) v /= n;
}

double ColourParticleFilter::bhattacharyya_distance(const std::vector<float>& a,
                                                    const std::vector<float>& b) {
    double rho = 0;  // eq. 5.7
    for (std::size_t i = 0; i < a.size(); ++i) rho += std::sqrt(static_cast<double>(a[i]) * b[i]);
    return std::sqrt(std::max(0.0, 1.0 - rho));  // eq. 5.10
}

cv::Rect ColourParticleFilter::box_of(const Particle& p) const {
    const double w = std::max(4.0, p[4]), h = std::max(4.0, p[5]);
    return cv::Rect(static_cast<int>(std::lround(p[0] - w / 2)),
                    static_cast<int>(std::lround(p[1] - h / 2)), static_cast<int>(std::lround(w)),
                    static_cast<int>(std::lround(h)));
}

void ColourParticleFilter::init(cv::Rect box) {
    histogram(box, reference_);
    reference_size_ = cv::Size2d(std::max(4, box.width), std::max(4, box.height));
    histogram(cv::Rect(0, 0, size_.width, size_.height), frame_hist_);
    // The tool's colours: twice as frequent in the reference as in the frame, and of
    // low saturation (steel and black plastic are grey; the book's observation that
    // the tool's region is darker or brighter than tissue, with its hue unreliable).
    for (std::size_t i = 0; i < reference_.size(); ++i)
        target_bin_[i] = reference_[i] > 2 * frame_hist_[i] &&
                         static_cast<int>(i) % params_.sat_bins <
                             params_.sat_bins * params_.max_tool_saturation / 256;
    for (Particle& p : particles_) {
        p = {box.x + box.width / 2.0 + rng_.gaussian(params_.position_noise),
             box.y + box.height / 2.0 + rng_.gaussian(params_.position_noise),
             0,
             0,
             box.width + rng_.gaussian(params_.size_noise),
             box.height + rng_.gaussian(params_.size_noise),
             0,
             0};
    }
    std::fill(weights_.begin(), weights_.end(), 1.0 / params_.particles);
    initialised_ = true;
    distance_ = 0;
}

bool ColourParticleFilter::is_target_colour(int y, int x) const {
    return target_bin_[bins_.at<std::uint8_t>(y, x)] != 0;
}

cv::Rect ColourParticleFilter::step() {
    // Prediction (eq. 5.6): constant velocity of the centre and the size, plus noise.
    double sum = 0;
    for (std::size_t i = 0; i < particles_.size(); ++i) {
        Particle& p = particles_[i];
        p[2] += rng_.gaussian(params_.velocity_noise);
        p[3] += rng_.gaussian(params_.velocity_noise);
        p[0] += p[2] + rng_.gaussian(params_.position_noise);
        p[1] += p[3] + rng_.gaussian(params_.position_noise);
        p[6] += rng_.gaussian(0.25 * params_.size_noise);
        p[7] += rng_.gaussian(0.25 * params_.size_noise);
        // The size stays within `size_range` of the reference's: along a shaft the
        // histogram cannot tell the rectangle's length, and it would wander off.
        p[4] = std::clamp(p[4] + p[6] + rng_.gaussian(params_.size_noise),
                          reference_size_.width / params_.size_range,
                          reference_size_.width * params_.size_range);
        p[5] = std::clamp(p[5] + p[7] + rng_.gaussian(params_.size_noise),
                          reference_size_.height / params_.size_range,
                          reference_size_.height * params_.size_range);
        // Weight (eq. 5.10-5.11).
        histogram(box_of(p), scratch_);
        const double d = bhattacharyya_distance(scratch_, reference_);
        weights_[i] *= std::exp(-params_.lambda * d * d);
        sum += weights_[i];
    }
    if (sum <= 0)
        std::fill(weights_.begin(), weights_.end(), 1.0 / params_.particles);
    else
        for (double& w : weights_) w /= sum;
    Particle mean{};
    for (std::size_t i = 0; i < particles_.size(); ++i)
        for (std::size_t k = 0; k < mean.size(); ++k) mean[k] += weights_[i] * particles_[i][k];
    const cv::Rect estimate = box_of(mean) & cv::Rect(0, 0, size_.width, size_.height);
    histogram(estimate, scratch_);
    distance_ = bhattacharyya_distance(scratch_, reference_);

    // Resampling when the effective sample size is low (eq. 5.12).
    const int n = params_.particles;
    if (effective_sample_size(weights_) < n / 2.0) {
        if (params_.sorted_resampling)
            sorted_resampling(weights_, order_, source_);
        else
            systematic_resampling(weights_, rng_.uniform(0.0, 1.0 / n), source_);
        for (std::size_t k = 0; k < particles_.size(); ++k)
            resampled_[k] = particles_[static_cast<std::size_t>(source_[k])];
        particles_.swap(resampled_);
        std::fill(weights_.begin(), weights_.end(), 1.0 / n);
    }
    return estimate;
}

}  // namespace endotower::vision::detail
