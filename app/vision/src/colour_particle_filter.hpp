// ColourParticleFilter: the book's colour particle filter (ch. 5, eq. 5.5-5.14) on a
// rectangle. State per particle (eq. 5.9): [xc, yc, xc', yc', w, h, w', h'];
// prediction by constant velocity plus Gaussian noise (eq. 5.6); the measurement is
// the rectangle's HSV hue-saturation histogram (`hue_bins` 8 x `sat_bins` 8, every
// second pixel), compared with the reference by the Bhattacharyya distance (eq. 5.10),
// weight w = exp(-lambda d^2) (eq. 5.11, lambda 20), normalised; the estimate is the
// weighted mean; resampling when N_eff = 1 / sum w^2 (eq. 5.12) falls below N / 2,
// systematic or, with `sorted_resampling`, the book's weight-sorted copies
// (eq. 5.13-5.14: the heaviest particle ceil(w N) times, then the next, until N).
// The rectangle's size stays within 1/`size_range` .. `size_range` (1.25) of the
// reference's. `lost()` when the estimate's own distance exceeds `lost_distance` (0.6).
// Private to app/vision; buffers sized in configure(), nothing allocated per frame.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <vector>

namespace endotower::vision::detail {

struct ColourParticleFilterParams {
    int particles = 100;
    int hue_bins = 8, sat_bins = 8;
    double lambda = 20;
    double position_noise = 4, velocity_noise = 1.5, size_noise = 1;
    double lost_distance = 0.6;
    int max_tool_saturation = 96;  // is_target_colour: HSV saturation below this
    double size_range = 1.25;      // the rectangle's size within 1/1.25 .. 1.25 x the reference's
    bool sorted_resampling = false;
    unsigned seed = 5;
};

class ColourParticleFilter {
public:
    using Particle = std::array<double, 8>;  // eq. 5.9
    explicit ColourParticleFilter(ColourParticleFilterParams params = {});
    void configure(cv::Size image);
    // Per frame, before init/step: the HSV bins of `bgr` (analysis size).
    void load(const cv::Mat& bgr);
    // Reference histogram of `box` in the loaded frame, particles spread about it.
    void init(cv::Rect box);
    bool initialised() const { return initialised_; }
    // Predict, weigh, estimate, resample; returns the estimated box.
    cv::Rect step();
    bool lost() const { return distance_ > params_.lost_distance; }
    double distance() const { return distance_; }
    // The tool's colour: P(bin) in the reference > 2 x P(bin) in the whole frame at
    // init, and saturation below `max_tool_saturation` (tools are grey).
    bool is_target_colour(int y, int x) const;

private:
    void histogram(cv::Rect box, std::vector<float>& h) const;
    static double bhattacharyya_distance(const std::vector<float>& a, const std::vector<float>& b);
    cv::Rect box_of(const Particle& p) const;

    ColourParticleFilterParams params_;
    cv::Mat hsv_, bins_;
    cv::Size size_;
    cv::Size2d reference_size_{8, 8};
    cv::RNG rng_;
    std::vector<Particle> particles_, resampled_;
    std::vector<double> weights_;
    std::vector<int> order_, source_;
    std::vector<float> reference_, frame_hist_, scratch_;
    std::vector<char> target_bin_;
    bool initialised_ = false;
    double distance_ = 1;
};

}  // namespace endotower::vision::detail
