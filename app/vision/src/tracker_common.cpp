#include "tracker_common.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "reduce_frame.hpp"

namespace endotower::vision::detail {

void AnalysisFrame::configure(const hal::FrameFormat& format, int analysis_width,
                              int surround_margin_px) {
    scale = std::min(1.0, static_cast<double>(analysis_width) / format.width);
    const int sw = std::max(1, static_cast<int>(std::lround(format.width * scale)));
    const int sh = std::max(1, static_cast<int>(std::lround(format.height * scale)));
    small.create(sh, sw, CV_8UC3);
    reduce.configure(format.width, format.height, sw, sh, 3);
    gray.create(sh, sw, CV_8UC1);
    lit.create(sh, sw, CV_8UC1);
    const int k = 2 * std::max(0, surround_margin_px) + 1;
    kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k));
    fov = {};
}

bool AnalysisFrame::load(const hal::Frame& frame) {
    if (frame.format.pixel_format != hal::PixelFormat::kBgr24 || small.empty() ||
        frame.data == nullptr)
        return false;
    reduce_frame(frame, reduce, small);
    cv::cvtColor(small, gray, cv::COLOR_BGR2GRAY);
    // The lit field of view, shrunk by the margin: the scope's rim is no tool edge.
    cv::threshold(gray, lit, surround_level, 255, cv::THRESH_BINARY);
    cv::erode(lit, lit, kernel);
    const cv::Moments m = cv::moments(lit, true);
    const double lit_fraction = m.m00 / (static_cast<double>(lit.rows) * lit.cols);
    fov = {};
    // A circle only where a dark surround exists; a fully lit frame ends at its border.
    if (m.m00 > 0 && lit_fraction < 0.9)
        fov = {m.m10 / m.m00, m.m01 / m.m00, std::sqrt(m.m00 / M_PI) + (kernel.cols - 1) / 2.0};
    return true;
}

hal::Frame AnalysisFrame::small_frame() const {
    hal::Frame f;
    f.format = {small.cols, small.rows, static_cast<int>(small.step), hal::PixelFormat::kBgr24};
    f.data = small.data;
    return f;
}

double AnalysisFrame::rim_distance(Point2 p) const {
    double d = std::min(std::min(p.x, p.y), std::min(small.cols - 1 - p.x, small.rows - 1 - p.y));
    if (fov.radius > 0) d = std::min(d, fov.radius - std::hypot(p.x - fov.cx, p.y - fov.cy));
    return d;
}

namespace {

void fill_estimate(const AnalysisFrame& a, Point2 incision, Point2 head, Point2 tip, double width,
                   const EdgePair& pair, int id, ToolEstimate& e) {
    const double inv = 1.0 / a.scale;
    auto full = [inv](Point2 p) { return Point2{p.x * inv, p.y * inv}; };
    e.id = id;
    e.present = true;
    e.tip = full(tip);
    e.head = full(head);
    e.axis_deg =
        std::atan2(incision.y - head.y, incision.x - head.x) * 180.0 / M_PI;  // tip -> incision
    e.width_px = width * inv;
    e.edges.found = true;
    e.edges.e1 = {full(pair.e1.a), full(pair.e1.b)};
    e.edges.e2 = {full(pair.e2.a), full(pair.e2.b)};
    e.edges.midline = {full(incision), e.head};
    e.edges.width_px = e.width_px;
}

}  // namespace

void describe_pair(const AnalysisFrame& a, const EdgePair& pair, int id, double jaw_length_widths,
                   const TipExtractorParams& tip_params, ToolEstimate& e) {
    // The incision side is the midline's end nearer the rim.
    const Point2 ma = pair.midline.a, mb = pair.midline.b;
    const bool a_is_incision = a.rim_distance(ma) <= a.rim_distance(mb);
    const Point2 incision = a_is_incision ? ma : mb, far = a_is_incision ? mb : ma;
    const double tl = std::max(1e-9, std::hypot(far.x - incision.x, far.y - incision.y));
    const double ux = (far.x - incision.x) / tl, uy = (far.y - incision.y) / tl;
    // The head: where the straight edges end on the tip side.
    double head_t = 0;
    for (Point2 p : {pair.e1.a, pair.e1.b, pair.e2.a, pair.e2.b})
        head_t = std::max(head_t, (p.x - incision.x) * ux + (p.y - incision.y) * uy);
    const Point2 head{incision.x + head_t * ux, incision.y + head_t * uy};
    // Jaws are a few shaft widths long: the tip is not farther than that beyond the head.
    TipExtractorParams tp = tip_params;
    if (tp.search_length_px <= 0) tp.search_length_px = jaw_length_widths * pair.width_px;
    const TipResult tip = extract_tip(a.small_frame(), pair, {ux, uy}, a.fov, tp);
    fill_estimate(a, incision, head, tip.found ? tip.tip : head, pair.width_px, pair, id, e);
    const double cover = std::min(pair.e1.length(), pair.e2.length()) / (0.25 * a.small.cols);
    e.confidence =
        std::clamp(0.25 + 0.5 * std::min(cover, 1.0) + (tip.found ? 0.25 : 0.0), 0.0, 1.0);
}

void RegionDescriber::configure(int width, int height) {
    histogram_.assign(static_cast<std::size_t>(2 * std::ceil(std::hypot(width, height)) + 3), 0);
}

bool RegionDescriber::describe(const AnalysisFrame& a, const cv::Mat& mask, cv::Rect roi,
                               const RegionShapeParams& params, int id, ToolEstimate& e) {
    roi &= cv::Rect(0, 0, mask.cols, mask.rows);
    if (roi.empty() || histogram_.empty()) return false;
    cv::Mat sub = mask(roi);
    if (params.largest_component) {
        // Scattered blobs of the tool's colour elsewhere would turn the axis.
        const int n = cv::connectedComponentsWithStats(sub, labels_, stats_, centroids_, 8, CV_32S);
        int best = 0;
        for (int i = 1; i < n; ++i)
            if (best == 0 ||
                stats_.at<int>(i, cv::CC_STAT_AREA) > stats_.at<int>(best, cv::CC_STAT_AREA))
                best = i;
        if (best == 0) return false;
        cv::compare(labels_, best, component_, cv::CMP_EQ);
        sub = component_;
    }
    const cv::Moments m = cv::moments(sub, true);
    if (m.m00 < params.min_area_fraction * mask.rows * mask.cols) return false;
    const double cx = m.m10 / m.m00, cy = m.m01 / m.m00;
    const double theta = 0.5 * std::atan2(2 * m.mu11, m.mu20 - m.mu02);
    const double dx = std::cos(theta), dy = std::sin(theta);

    // Extent along the axis: a histogram of the pixels' projections (1 px bins).
    const int half = static_cast<int>(histogram_.size() / 2);
    std::fill(histogram_.begin(), histogram_.end(), 0);
    for (int y = 0; y < sub.rows; ++y) {
        const std::uint8_t* row = sub.ptr<std::uint8_t>(y);
        for (int x = 0; x < sub.cols; ++x)
            if (row[x])
                ++histogram_[static_cast<std::size_t>(half +
                                                      std::lround((x - cx) * dx + (y - cy) * dy))];
    }
    const auto area = static_cast<long>(m.m00);
    auto quantile = [&](double q) {
        long seen = 0;
        const long target = static_cast<long>(q * static_cast<double>(area));
        for (std::size_t i = 0; i < histogram_.size(); ++i)
            if ((seen += histogram_[i]) > target)
                return static_cast<double>(static_cast<int>(i) - half);
        return static_cast<double>(static_cast<int>(histogram_.size()) - 1 - half);
    };
    const double t_lo = quantile(0.005), t_hi = quantile(0.995);
    const double length = t_hi - t_lo;
    if (length <= 0) return false;
    const double width = m.m00 / length;
    if (length < params.min_elongation * width) return false;

    const Point2 end_lo{roi.x + cx + t_lo * dx, roi.y + cy + t_lo * dy};
    const Point2 end_hi{roi.x + cx + t_hi * dx, roi.y + cy + t_hi * dy};
    bool lo_is_incision = a.rim_distance(end_lo) <= a.rim_distance(end_hi);
    if (std::isfinite(params.tip_direction_deg) &&
        std::abs(a.rim_distance(end_lo) - a.rim_distance(end_hi)) < width) {
        const double r = params.tip_direction_deg * M_PI / 180.0;
        lo_is_incision = std::cos(r) * dx + std::sin(r) * dy >= 0;  // +d points along the motion
    }
    const Point2 incision = lo_is_incision ? end_lo : end_hi;
    const double sign = lo_is_incision ? 1.0 : -1.0;  // along +d towards the tip?
    const double t_tip = lo_is_incision ? t_hi : t_lo;
    // The tip: mean of the pixels in the far end's last few per cent of the length.
    const double band = std::max(1.0, params.tip_fraction * length);
    double sx = 0, sy = 0, n = 0;
    for (int y = 0; y < sub.rows; ++y) {
        const std::uint8_t* row = sub.ptr<std::uint8_t>(y);
        for (int x = 0; x < sub.cols; ++x) {
            if (!row[x]) continue;
            const double t = (x - cx) * dx + (y - cy) * dy;
            if (sign * (t_tip - t) <= band) {
                sx += x;
                sy += y;
                n += 1;
            }
        }
    }
    const Point2 tip =
        n > 0 ? Point2{roi.x + sx / n, roi.y + sy / n} : (lo_is_incision ? end_hi : end_lo);
    const double ux = sign * dx, uy = sign * dy;
    const double head_back = std::min(params.head_widths * width, 0.5 * length);
    const Point2 head{tip.x - head_back * ux, tip.y - head_back * uy};
    const double nx = -uy * width / 2, ny = ux * width / 2;
    EdgePair pair;
    pair.found = true;
    pair.e1 = {{incision.x + nx, incision.y + ny}, {head.x + nx, head.y + ny}};
    pair.e2 = {{incision.x - nx, incision.y - ny}, {head.x - nx, head.y - ny}};
    pair.midline = {incision, head};
    pair.width_px = width;
    fill_estimate(a, incision, head, tip, width, pair, id, e);
    // Longer and thinner regions are surer tools.
    e.confidence = std::clamp(0.3 + 0.1 * (length / width - params.min_elongation), 0.3, 1.0);
    return true;
}

double line_angle_deg(double a_deg, double b_deg) {
    const double d = std::abs(std::remainder(a_deg - b_deg, 180.0));
    return std::min(d, 180.0 - d);
}

}  // namespace endotower::vision::detail
