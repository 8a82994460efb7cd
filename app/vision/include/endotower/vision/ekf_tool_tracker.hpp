// EkfToolTracker: the book's extended Kalman filter on the tool's two edges in polar
// form (ch. 4, eq. 4.17-4.21, fig. 4.14-4.16), tracker name `ekf`.
// State X = [x, y, u, v, w, theta1, rho1, theta2, rho2]: the centre of rotation, its
// velocity, the angular velocity and the edges as rho = x cos(theta) + y sin(theta);
// f() of eq. 4.18 (constant translation and rotation about (x, y)), its Jacobian A
// (eq. 4.20) in closed form, the measurement of both edges' (theta, rho), M of eq. 4.21.
// Measurement (fig. 4.16): Canny on the frame reduced to `analysis_width` (640), then a
// Hough accumulator voted only inside each edge's predicted window (theta +-
// `window_theta_deg` 4, rho +- `window_rho_px` 12, narrowed to 0.4 x the edge
// spacing so both edges cannot take one peak); the window's peak is the edge when it
// has `min_votes_fraction` (0.06) x the analysis width votes. Polar lines have no
// slope singularity: a vertical tool is tracked like any other.
// Initialisation, and re-initialisation once more than `max_missed` (0) frames in a
// row lack both edges (in that same frame): Canny + probabilistic Hough +
// EdgePairing, as the midline tracker. 0 measured best (docs/tracking.md). The edges'
// extent is the longest run of edge pixels along each line (gaps up to 10 px); the tip
// along the midline with TipExtractor (describe: tip, head, axis in full resolution).
// One tool (the book's EKF tracks one). Buffers sized in configure(); nothing is
// allocated per frame.
#pragma once

#include <memory>

#include "endotower/vision/tip_extractor.hpp"
#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

struct EkfToolTrackerParams {
    int analysis_width = 640;
    double canny_low = 40, canny_high = 120;
    double window_theta_deg = 4.0, theta_step_deg = 0.5;
    double window_rho_px = 12.0;
    double min_votes_fraction = 0.06;
    int max_missed = 0;
    double process_noise_xy = 4.0, process_noise_uv = 1.0, process_noise_w = 1e-4;
    double process_noise_theta = 1e-4, process_noise_rho = 4.0;
    double measurement_noise_theta = 1e-4, measurement_noise_rho = 1.0;
    // Initialisation (as KalmanToolTracker): Hough threshold, minimum segment length
    // (fraction of the analysis width), plausible shaft width.
    int hough_threshold = 50;
    double min_length_fraction = 0.08;
    double min_width_px = 6, max_width_fraction = 0.3;
    int surround_margin_px = 8;
    double jaw_length_widths = 4.0;
    TipExtractorParams tip{.last_strong_change = true, .use_saturation = true};
};

class EkfToolTracker final : public ToolTracker {
public:
    explicit EkfToolTracker(EkfToolTrackerParams params = {});
    ~EkfToolTracker() override;
    std::string_view name() const override { return "ekf"; }
    void configure(const hal::FrameFormat& format) override;
    std::size_t track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) override;

private:
    struct Work;
    EkfToolTrackerParams params_;
    std::unique_ptr<Work> work_;
    int next_id_ = 0;
};

}  // namespace endotower::vision
