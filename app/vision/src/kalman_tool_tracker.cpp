#include "endotower/vision/kalman_tool_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <span>
#include <vector>

#include "endotower/vision/area_mean.hpp"

namespace endotower::vision {

struct KalmanToolTracker::Work {
    double scale = 1.0;  // analysis pixels per full-resolution pixel
    cv::Mat small, gray, edges, lit, kernel;
    AreaMean reduce;  // INTER_AREA without cv::resize's per-call allocation
    std::vector<cv::Vec4i> lines;
    std::vector<Segment> segments, gated;
    std::vector<char> used;  // segment already explains a tracked tool
};

namespace {

double border_distance(Point2 p, int w, int h) {
    return std::min(std::min(p.x, p.y), std::min(w - 1 - p.x, h - 1 - p.y));
}

bool plausible(const EdgePair& p, const KalmanToolTrackerParams& k, int width) {
    return p.found && p.width_px >= k.min_width_px && p.width_px <= k.max_width_fraction * width;
}

}  // namespace

KalmanToolTracker::KalmanToolTracker(KalmanToolTrackerParams params)
    : params_(params), work_(std::make_unique<Work>()) {
    for (Track& t : tracks_) t.kalman = MidlineKalman(params_.kalman);
}

KalmanToolTracker::~KalmanToolTracker() = default;

void KalmanToolTracker::configure(const hal::FrameFormat& format) {
    Work& w = *work_;
    w.scale = std::min(1.0, static_cast<double>(params_.analysis_width) / format.width);
    const int sw = std::max(1, static_cast<int>(std::lround(format.width * w.scale)));
    const int sh = std::max(1, static_cast<int>(std::lround(format.height * w.scale)));
    w.small.create(sh, sw, CV_8UC3);
    w.reduce.configure(format.width, format.height, sw, sh, 3);
    w.gray.create(sh, sw, CV_8UC1);
    w.edges.create(sh, sw, CV_8UC1);
    w.lit.create(sh, sw, CV_8UC1);
    w.kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * params_.surround_margin_px + 1, 2 * params_.surround_margin_px + 1));
    w.lines.reserve(4096);
    w.segments.reserve(4096);
    w.gated.reserve(4096);
    w.used.reserve(4096);
    for (Track& t : tracks_) t = Track{MidlineKalman(params_.kalman), -1};
}

std::size_t KalmanToolTracker::track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) {
    Work& w = *work_;
    if (frame.format.pixel_format != hal::PixelFormat::kBgr24 || w.small.empty()) return 0;
    const cv::Mat full(frame.format.height, frame.format.width, CV_8UC3, frame.data, frame.format.stride);
    if (w.reduce.fits(frame.format.width, frame.format.height))
        w.reduce.run(frame.data, frame.format.stride, w.small.data, w.small.step);
    else if (w.scale < 1.0) cv::resize(full, w.small, w.small.size(), 0, 0, cv::INTER_AREA);
    else full.copyTo(w.small);

    if (params_.red_binarised) {
        // Fig. 4.12-4.13: tissue is bright in red, tools are not.
        cv::extractChannel(w.small, w.gray, 2);
        cv::threshold(w.gray, w.gray, params_.red_threshold, 255, cv::THRESH_BINARY);
    } else {
        cv::cvtColor(w.small, w.gray, cv::COLOR_BGR2GRAY);
        cv::GaussianBlur(w.gray, w.gray, cv::Size(5, 5), 1.5);
    }
    cv::Canny(w.gray, w.edges, params_.canny_low, params_.canny_high);
    if (params_.surround_margin_px > 0) {
        // Nothing outside the scope's lit circle: its rim is the strongest edge of
        // the picture and no tool edge.
        cv::cvtColor(w.small, w.lit, cv::COLOR_BGR2GRAY);
        cv::threshold(w.lit, w.lit, params_.surround_level, 255, cv::THRESH_BINARY);
        cv::erode(w.lit, w.lit, w.kernel);
        cv::bitwise_and(w.edges, w.lit, w.edges);
    }
    w.lines.clear();
    cv::HoughLinesP(w.edges, w.lines, 1, CV_PI / 360, params_.hough_threshold,
                    params_.min_length_fraction * w.small.cols, params_.max_gap_px);
    w.segments.clear();
    for (const cv::Vec4i& l : w.lines)
        w.segments.push_back({{double(l[0]), double(l[1])}, {double(l[2]), double(l[3])}});
    std::sort(w.segments.begin(), w.segments.end(),
              [](const Segment& a, const Segment& b) { return a.length() > b.length(); });

    // Fig. 4.22: one filter per tool. Active filters take their gated segments
    // first; a free filter starts on the strongest pair among what is left.
    w.used.assign(w.segments.size(), 0);
    std::size_t n = 0;
    const std::span<Track> tracks(tracks_.data(), std::min(params_.max_tools, tracks_.size()));
    for (Track& t : tracks) {
        if (!t.kalman.initialised() || t.kalman.lost()) continue;
        t.kalman.predict();
        w.gated.clear();
        for (std::size_t i = 0; i < w.segments.size(); ++i)
            if (!w.used[i] && t.kalman.gate(w.segments[i])) w.gated.push_back(w.segments[i]);
        const EdgePair pair = pair_edges(w.gated);
        if (!plausible(pair, params_, w.small.cols)) {
            t.kalman.miss();
            continue;
        }
        t.kalman.correct(pair.midline);
        mark_used(pair);
        if (n < out.size()) describe(pair, t.id, out[n++]);
    }
    for (Track& t : tracks) {
        if (t.kalman.initialised() && !t.kalman.lost()) continue;
        w.gated.clear();
        for (std::size_t i = 0; i < w.segments.size(); ++i)
            if (!w.used[i]) w.gated.push_back(w.segments[i]);
        const EdgePair pair = pair_edges(w.gated);
        if (!plausible(pair, params_, w.small.cols)) break;  // nothing left for later slots either
        t.kalman.init(pair.midline);
        t.id = next_id_++;
        mark_used(pair);
        if (n < out.size()) describe(pair, t.id, out[n++]);
    }
    return n;
}

void KalmanToolTracker::mark_used(const EdgePair& pair) {
    Work& w = *work_;
    for (std::size_t i = 0; i < w.segments.size(); ++i)
        if (max_end_distance(w.segments[i], pair.e1) <= params_.used_distance_px ||
            max_end_distance(w.segments[i], pair.e2) <= params_.used_distance_px)
            w.used[i] = 1;
}

void KalmanToolTracker::describe(const EdgePair& pair, int id, ToolEstimate& e) {
    Work& w = *work_;
    // The incision side is the midline's end nearer the image border.
    const Point2 a = pair.midline.a, b = pair.midline.b;
    const bool a_is_incision = border_distance(a, w.small.cols, w.small.rows) <= border_distance(b, w.small.cols, w.small.rows);
    const Point2 incision = a_is_incision ? a : b, far = a_is_incision ? b : a;
    const Point2 toward_tip{far.x - incision.x, far.y - incision.y};

    hal::Frame small_frame;
    small_frame.format = {w.small.cols, w.small.rows, static_cast<int>(w.small.step), hal::PixelFormat::kBgr24};
    small_frame.data = w.small.data;
    // The field of view as the lit area's equivalent circle (the calibration's
    // circle takes its place once a calibrated scope is configured).
    FieldOfView fov;
    if (params_.surround_margin_px > 0) {
        const cv::Moments m = cv::moments(w.lit, true);
        if (m.m00 > 0) fov = {m.m10 / m.m00, m.m01 / m.m00, std::sqrt(m.m00 / M_PI) + params_.surround_margin_px};
    }
    // Jaws are a few shaft diameters long: the tip is not farther than that beyond
    // the end of the straight edges.
    TipExtractorParams tip_params = params_.tip;
    if (tip_params.search_length_px <= 0) tip_params.search_length_px = params_.jaw_length_widths * pair.width_px;
    const TipResult tip = extract_tip(small_frame, pair, toward_tip, fov, tip_params);

    // The head: where the straight edges end on the tip side, on the midline.
    const double tl = std::hypot(toward_tip.x, toward_tip.y);
    const double ux = toward_tip.x / tl, uy = toward_tip.y / tl;
    double head_t = 0;
    for (Point2 p : {pair.e1.a, pair.e1.b, pair.e2.a, pair.e2.b})
        head_t = std::max(head_t, (p.x - incision.x) * ux + (p.y - incision.y) * uy);
    const Point2 head{incision.x + head_t * ux, incision.y + head_t * uy};
    const Point2 tip_pt = tip.found ? tip.tip : head;

    const double inv = 1.0 / w.scale;
    e.id = id;
    e.present = true;
    e.tip = {tip_pt.x * inv, tip_pt.y * inv};
    e.head = {head.x * inv, head.y * inv};
    e.axis_deg = std::atan2(-uy, -ux) * 180.0 / M_PI;  // tip -> incision
    e.width_px = pair.width_px * inv;
    e.edges.found = true;
    e.edges.e1 = {{pair.e1.a.x * inv, pair.e1.a.y * inv}, {pair.e1.b.x * inv, pair.e1.b.y * inv}};
    e.edges.e2 = {{pair.e2.a.x * inv, pair.e2.a.y * inv}, {pair.e2.b.x * inv, pair.e2.b.y * inv}};
    e.edges.midline = {{incision.x * inv, incision.y * inv}, {e.head.x, e.head.y}};
    e.edges.width_px = e.width_px;
    // Longer edges on both sides and a clear tip make a surer estimate.
    const double cover = std::min(pair.e1.length(), pair.e2.length()) / (0.25 * w.small.cols);
    e.confidence = std::clamp(0.25 + 0.5 * std::min(cover, 1.0) + (tip.found ? 0.25 : 0.0), 0.0, 1.0);
}

}  // namespace endotower::vision
