// MidlineKalman: the book's standard Kalman filter on a tool's midline (ch. 4,
// eq. 4.4-4.16): state X = [m, b, m', b'] of the line y = m x + b, constant-velocity
// transition (eq. 4.9), measurement of [m, b] (eq. 4.10), Q = 80 I and
// R = [[0.005, 0.005], [0.005, 0.005]] (eq. 4.11).
//
// Beyond the book: a steep tool is filtered as x = m y + b (the state is converted
// and its velocities restarted when the predicted line passes `swap_slope`), so a
// vertical tool has no slope singularity.
// Gating (the book's |m_midline - m_edge| < eps and d_max < eps): an edge is the
// tool's when its slope, in the filter's parameterisation, is within `gate_slope`
// of the predicted midline and its end points within `gate_distance_px` of it.
// Loss: after `max_missed` frames without a measurement the filter reports lost()
// and must be initialised again.
// Uses OpenCV's cv::KalmanFilter; no allocation after init().
#pragma once

#include <memory>

#include "endotower/vision/line2.hpp"

namespace endotower::vision {

struct MidlineKalmanParams {
    double process_noise = 80.0;       // Q diagonal (eq. 4.11)
    double measurement_noise = 0.005;  // every entry of R (eq. 4.11)
    double swap_slope = 1.5;           // |m| beyond which the axes are swapped
    double gate_slope = 0.2;
    double gate_distance_px = 40.0;
    int max_missed = 5;
};

class MidlineKalman {
public:
    explicit MidlineKalman(MidlineKalmanParams params = {});
    ~MidlineKalman();
    MidlineKalman(MidlineKalman&&) noexcept;
    MidlineKalman& operator=(MidlineKalman&&) noexcept;

    void init(const Segment& midline);
    bool initialised() const { return initialised_; }
    bool lost() const { return missed_ > params_.max_missed; }

    // Time update; returns the a priori midline.
    SlopeLine predict();
    // Measurement update with the measured midline; returns the posterior midline.
    SlopeLine correct(const Segment& measured);
    // No measurement this frame: the prediction stands.
    void miss() { ++missed_; }

    bool gate(const Segment& edge) const;
    // The current estimate (posterior after correct(), prior after predict()).
    SlopeLine midline() const { return line_; }

private:
    void set_state(const SlopeLine& l, double dm, double db);

    MidlineKalmanParams params_;
    struct Filter;
    std::unique_ptr<Filter> filter_;
    SlopeLine line_{};
    bool initialised_ = false;
    int missed_ = 0;
};

}  // namespace endotower::vision
