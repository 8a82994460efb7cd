#include "endotower/vision/ekf_tool_tracker.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "tracker_common.hpp"

namespace endotower::vision {

namespace {

using State = Eigen::Matrix<double, 9, 1>;
using Cov = Eigen::Matrix<double, 9, 9>;
enum { kX, kY, kU, kV, kW, kT1, kR1, kT2, kR2 };

struct Polar {
    double theta = 0, rho = 0;
};

Polar polar_of(const Segment& s) {
    const double dx = s.b.x - s.a.x, dy = s.b.y - s.a.y, l = std::max(1e-9, std::hypot(dx, dy));
    const double nx = -dy / l, ny = dx / l;
    return {std::atan2(ny, nx), nx * s.a.x + ny * s.a.y};
}

// The same line with theta within pi/2 of `near` (theta + pi is the line with -rho).
Polar aligned(Polar p, double near) {
    while (p.theta - near > M_PI / 2) p = {p.theta - M_PI, -p.rho};
    while (p.theta - near < -M_PI / 2) p = {p.theta + M_PI, -p.rho};
    return p;
}

}  // namespace

struct EkfToolTracker::Work {
    detail::AnalysisFrame frame;
    cv::Mat blurred, edges;
    std::vector<cv::Point> pixels;  // edge pixels in view
    std::vector<cv::Vec4i> lines;
    std::vector<Segment> segments;
    std::vector<int> votes;  // one Hough window
    std::vector<int> run;    // pixels along a line, 1 px bins
    State x = State::Zero();
    Cov p = Cov::Identity();
    bool tracking = false;
    int missed = 0, id = -1;
};

EkfToolTracker::EkfToolTracker(EkfToolTrackerParams params)
    : params_(params), work_(std::make_unique<Work>()) {}

EkfToolTracker::~EkfToolTracker() = default;

void EkfToolTracker::configure(const hal::FrameFormat& format) {
    Work& w = *work_;
    w.frame.configure(format, params_.analysis_width, params_.surround_margin_px);
    const cv::Size sz = w.frame.small.size();
    w.blurred.create(sz, CV_8UC1);
    w.edges.create(sz, CV_8UC1);
    w.pixels.reserve(static_cast<std::size_t>(sz.area()));
    w.lines.reserve(4096);
    w.segments.reserve(4096);
    const int nt =
        2 * static_cast<int>(std::ceil(params_.window_theta_deg / params_.theta_step_deg)) + 1;
    const int nr = 2 * static_cast<int>(std::ceil(params_.window_rho_px)) + 1;
    w.votes.assign(static_cast<std::size_t>(nt) * static_cast<std::size_t>(nr), 0);
    w.run.assign(static_cast<std::size_t>(2 * std::ceil(std::hypot(sz.width, sz.height)) + 3), 0);
    w.tracking = false;
}

namespace {

// Fig. 4.16: the Hough peak inside the window around the predicted edge.
bool window_peak(const std::vector<cv::Point>& pixels, Polar predicted, double half_theta,
                 double step, double half_rho, int min_votes, std::vector<int>& votes,
                 Polar& peak) {
    const int kt = static_cast<int>(std::ceil(half_theta / step));
    const int kr = static_cast<int>(std::ceil(half_rho));
    const int nr = 2 * kr + 1;
    std::fill(votes.begin(), votes.begin() + (2 * kt + 1) * nr, 0);
    for (int i = -kt; i <= kt; ++i) {
        const double th = predicted.theta + i * step;
        const double c = std::cos(th), s = std::sin(th);
        int* row = votes.data() + (i + kt) * nr;
        for (const cv::Point& q : pixels) {
            const double d = q.x * c + q.y * s - predicted.rho;
            if (d > -half_rho - 0.5 && d < half_rho + 0.5) {
                const int j = static_cast<int>(std::lround(d)) + kr;
                if (j >= 0 && j < nr) ++row[j];
            }
        }
    }
    int best = -1, bi = 0, bj = 0;
    for (int i = 0; i < 2 * kt + 1; ++i)
        for (int j = 0; j < nr; ++j) {
            const int v = votes[static_cast<std::size_t>(i) * static_cast<std::size_t>(nr) +
                                static_cast<std::size_t>(j)];
            if (v > best) {
                best = v;
                bi = i;
                bj = j;
            }
        }
    if (best < min_votes) return false;
    peak = {predicted.theta + (bi - kt) * step, predicted.rho + (bj - kr)};
    return true;
}

// The longest run of edge pixels within 2 px of the line (gaps up to `gap` px).
bool line_extent(const std::vector<cv::Point>& pixels, Polar l, double gap, std::vector<int>& run,
                 Segment& out) {
    const double c = std::cos(l.theta), s = std::sin(l.theta);
    const double px = l.rho * c, py = l.rho * s;  // foot of the origin's perpendicular
    const double dx = -s, dy = c;
    const int half = static_cast<int>(run.size() / 2);
    std::fill(run.begin(), run.end(), 0);
    for (const cv::Point& q : pixels) {
        if (std::abs(q.x * c + q.y * s - l.rho) > 2.0) continue;
        const long t = std::lround((q.x - px) * dx + (q.y - py) * dy) + half;
        if (t >= 0 && t < static_cast<long>(run.size())) run[static_cast<std::size_t>(t)] = 1;
    }
    int best_len = 0, best_a = 0, start = -1, last = -1;
    for (int t = 0; t < static_cast<int>(run.size()); ++t) {
        if (!run[static_cast<std::size_t>(t)]) continue;
        if (start < 0 || t - last > gap) start = t;
        last = t;
        if (last - start > best_len) {
            best_len = last - start;
            best_a = start;
        }
    }
    if (best_len <= 0) return false;
    const double ta = best_a - half, tb = best_a + best_len - half;
    out = {{px + ta * dx, py + ta * dy}, {px + tb * dx, py + tb * dy}};
    return true;
}

}  // namespace

std::size_t EkfToolTracker::track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) {
    Work& w = *work_;
    if (!w.frame.load(frame)) return 0;
    const cv::Mat& small = w.frame.small;
    cv::GaussianBlur(w.frame.gray, w.blurred, cv::Size(5, 5), 1.5);
    cv::Canny(w.blurred, w.edges, params_.canny_low, params_.canny_high);
    if (params_.surround_margin_px > 0) cv::bitwise_and(w.edges, w.frame.lit, w.edges);
    w.pixels.clear();
    for (int y = 0; y < w.edges.rows; ++y) {
        const std::uint8_t* row = w.edges.ptr<std::uint8_t>(y);
        for (int x = 0; x < w.edges.cols; ++x)
            if (row[x]) w.pixels.emplace_back(x, y);
    }
    const double deg = M_PI / 180.0;
    const int min_votes = static_cast<int>(params_.min_votes_fraction * small.cols);

    Polar e1, e2;
    bool measured = false;
    if (w.tracking) {
        // Prediction, eq. 4.18, and its Jacobian, eq. 4.20.
        const State& s = w.x;
        State xp = s;
        Cov a = Cov::Identity();
        xp(kX) = s(kX) + s(kU);
        xp(kY) = s(kY) + s(kV);
        a(kX, kU) = a(kY, kV) = 1;
        for (int k : {kT1, kT2}) {
            const int r = k + 1;
            const double th = s(k), th1 = s(k) + s(kW);
            xp(k) = th1;
            a(k, kW) = 1;
            xp(r) = s(r) - s(kX) * std::cos(th) - s(kY) * std::sin(th) + xp(kX) * std::cos(th1) +
                    xp(kY) * std::sin(th1);
            a(r, kX) = -std::cos(th) + std::cos(th1);
            a(r, kY) = -std::sin(th) + std::sin(th1);
            a(r, kU) = std::cos(th1);
            a(r, kV) = std::sin(th1);
            const double dth1 = -xp(kX) * std::sin(th1) + xp(kY) * std::cos(th1);
            a(r, kW) = dth1;
            a(r, k) = s(kX) * std::sin(th) - s(kY) * std::cos(th) + dth1;
        }
        Eigen::Matrix<double, 9, 1> q;
        q << params_.process_noise_xy, params_.process_noise_xy, params_.process_noise_uv,
            params_.process_noise_uv, params_.process_noise_w, params_.process_noise_theta,
            params_.process_noise_rho, params_.process_noise_theta, params_.process_noise_rho;
        w.x = xp;
        w.p = a * w.p * a.transpose();
        w.p.diagonal() += q;

        const Polar p1{w.x(kT1), w.x(kR1)}, p2{w.x(kT2), w.x(kR2)};
        const double spacing = std::abs(aligned(p2, p1.theta).rho - p1.rho);
        const double half_rho = std::clamp(0.4 * spacing, 2.0, params_.window_rho_px);
        measured = window_peak(w.pixels, p1, params_.window_theta_deg * deg,
                               params_.theta_step_deg * deg, half_rho, min_votes, w.votes, e1) &&
                   window_peak(w.pixels, p2, params_.window_theta_deg * deg,
                               params_.theta_step_deg * deg, half_rho, min_votes, w.votes, e2) &&
                   // Two peaks closer than a shaft's width are one edge found twice.
                   std::abs(aligned(e2, e1.theta).rho - e1.rho) >= params_.min_width_px;
        if (measured) {
            // Correction with M of eq. 4.21: the state's edge parameters are measured.
            Eigen::Matrix<double, 4, 9> m = Eigen::Matrix<double, 4, 9>::Zero();
            m(0, kT1) = m(1, kR1) = m(2, kT2) = m(3, kR2) = 1;
            Eigen::Vector4d z(e1.theta, e1.rho, e2.theta, e2.rho);
            const Eigen::Vector4d r(params_.measurement_noise_theta, params_.measurement_noise_rho,
                                    params_.measurement_noise_theta, params_.measurement_noise_rho);
            Eigen::Matrix4d sm = m * w.p * m.transpose();
            sm.diagonal() += r;
            const Eigen::Matrix<double, 9, 4> k = w.p * m.transpose() * sm.inverse();
            w.x += k * (z - m * w.x);
            w.p = (Cov::Identity() - k * m) * w.p;
            w.missed = 0;
            // The edges' extent is read along the measured lines (the posterior is
            // smoothed and may sit a pixel off the edge pixels).
        } else if (++w.missed > params_.max_missed) {
            w.tracking = false;
        }
    }
    if (!w.tracking) {
        // (Re-)initialisation from the strongest plausible edge pair.
        w.lines.clear();
        cv::HoughLinesP(w.edges, w.lines, 1, CV_PI / 360, params_.hough_threshold,
                        params_.min_length_fraction * small.cols, 10);
        w.segments.clear();
        for (const cv::Vec4i& l : w.lines)
            w.segments.push_back({{double(l[0]), double(l[1])}, {double(l[2]), double(l[3])}});
        std::sort(w.segments.begin(), w.segments.end(),
                  [](const Segment& a, const Segment& b) { return a.length() > b.length(); });
        const EdgePair pair = pair_edges(w.segments);
        if (!pair.found || pair.width_px < params_.min_width_px ||
            pair.width_px > params_.max_width_fraction * small.cols)
            return 0;
        e1 = polar_of(pair.e1);
        e2 = aligned(polar_of(pair.e2), e1.theta);
        w.x = State::Zero();
        w.x(kX) = 0.5 * (pair.midline.a.x + pair.midline.b.x);
        w.x(kY) = 0.5 * (pair.midline.a.y + pair.midline.b.y);
        w.x(kT1) = e1.theta;
        w.x(kR1) = e1.rho;
        w.x(kT2) = e2.theta;
        w.x(kR2) = e2.rho;
        w.p = Cov::Identity();
        w.p.diagonal() << 25, 25, 25, 25, 1e-2, 1e-3, 4, 1e-3, 4;
        w.tracking = true;
        w.missed = 0;
        w.id = next_id_++;
        measured = true;
    }
    if (!measured) return 0;  // coasting: no tool is claimed without its edges

    EdgePair pair;
    if (!line_extent(w.pixels, e1, 10, w.run, pair.e1) ||
        !line_extent(w.pixels, e2, 10, w.run, pair.e2))
        return 0;
    // The midline: halfway between the edges, over both edges' extent.
    const Polar mid{0.5 * (e1.theta + e2.theta), 0.5 * (e1.rho + aligned(e2, e1.theta).rho)};
    const double c = std::cos(mid.theta), s = std::sin(mid.theta), dx = -s, dy = c;
    double t_lo = 1e18, t_hi = -1e18;
    for (Point2 q : {pair.e1.a, pair.e1.b, pair.e2.a, pair.e2.b}) {
        const double t = q.x * dx + q.y * dy;
        t_lo = std::min(t_lo, t);
        t_hi = std::max(t_hi, t);
    }
    pair.midline = {{mid.rho * c + t_lo * dx, mid.rho * s + t_lo * dy},
                    {mid.rho * c + t_hi * dx, mid.rho * s + t_hi * dy}};
    const Point2 centre{0.5 * (pair.midline.a.x + pair.midline.b.x),
                        0.5 * (pair.midline.a.y + pair.midline.b.y)};
    pair.width_px = distance_to_line(centre, pair.e1) + distance_to_line(centre, pair.e2);
    pair.found = true;
    if (pair.width_px < params_.min_width_px ||
        pair.width_px > params_.max_width_fraction * small.cols)
        return 0;
    detail::describe_pair(w.frame, pair, w.id, params_.jaw_length_widths, params_.tip, out[0]);
    return 1;
}

}  // namespace endotower::vision
