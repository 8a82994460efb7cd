#include "endotower/vision/region_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "high_pass_window.hpp"
#include "pyramid_lk.hpp"
#include "ransac_homography.hpp"
#include "region_matching.hpp"

namespace endotower::vision {

namespace {

// LK: a 15x15 window, levels 0..3 (OpenCV's maxLevel 3), 20 iterations, 0.03 px.
constexpr detail::LkParams kLk{.window = 15, .max_level = 3, .max_iterations = 20, .epsilon = 0.03};
// Detections keep the strongest features: matching is brute force, so its cost is
// the product of the two counts.
constexpr int kFrameFeatures = 1000;
constexpr int kKeyframeFeatures = 500;
constexpr int kTrackCorners = 150;
constexpr int kShadingBox = 15;
constexpr int kLkMaxWidth = 960;

double lk_scale(int frame_width) {
    return frame_width > kLkMaxWidth ? static_cast<double>(kLkMaxWidth) / frame_width : 1.0;
}
// Keyframe and propagated polygons closer than this (mean corner distance, working
// pixels) agree: the propagation is kept.
constexpr double kAgreePx = 1.0;
// Fraction of the followed points that must fit the propagated homography.
constexpr double kMinAgreeing = 0.4;
// A homography may not grow or shrink the region more than this (in area).
constexpr double kMaxAreaRatio = 25.0;
// Below this fraction of its bounding box in the picture a region counts as gone.
constexpr double kMinVisible = 0.2;
// Tissue bends: followed points off the region's homography by up to this fraction of
// the region's size (sqrt of its area) are kept as its local motion, not as outliers.
constexpr double kBendFraction = 0.15;
// The local motion at a vertex: points weighted by a Gaussian of this fraction of the
// region's size around the vertex (keyframe positions).
constexpr double kBendSigma = 0.2;

bool supported(const hal::Frame& f) {
    using hal::PixelFormat;
    const PixelFormat p = f.format.pixel_format;
    return f.data != nullptr && f.format.width > 0 && f.format.height > 0 &&
           (p == PixelFormat::kBgr24 || p == PixelFormat::kRgb24 || p == PixelFormat::kBgra32 ||
            p == PixelFormat::kGray8);
}

// The grey image of `roi` of a supported frame.
void to_gray(const hal::Frame& f, cv::Rect roi, cv::Mat& gray) {
    const int w = f.format.width, h = f.format.height;
    const auto step = static_cast<std::size_t>(f.format.stride);
    switch (f.format.pixel_format) {
        case hal::PixelFormat::kBgr24:
            cv::cvtColor(cv::Mat(h, w, CV_8UC3, f.data, step)(roi), gray, cv::COLOR_BGR2GRAY);
            break;
        case hal::PixelFormat::kRgb24:
            cv::cvtColor(cv::Mat(h, w, CV_8UC3, f.data, step)(roi), gray, cv::COLOR_RGB2GRAY);
            break;
        case hal::PixelFormat::kBgra32:
            cv::cvtColor(cv::Mat(h, w, CV_8UC4, f.data, step)(roi), gray, cv::COLOR_BGRA2GRAY);
            break;
        default:
            cv::Mat(h, w, CV_8UC1, f.data, step)(roi).copyTo(gray);
            break;
    }
}

double signed_area(const std::vector<cv::Point2f>& p) {
    double a = 0;
    for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
        a += double(p[j].x) * p[i].y - double(p[i].x) * p[j].y;
    return a / 2;
}

double mean_distance(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b) {
    double s = 0;
    for (std::size_t i = 0; i < a.size(); ++i) s += cv::norm(a[i] - b[i]);
    return s / static_cast<double>(a.size());
}

cv::Rect2f bounds(const std::vector<cv::Point2f>& poly) {
    float x0 = poly[0].x, y0 = poly[0].y, x1 = x0, y1 = y0;
    for (const cv::Point2f& p : poly)
        x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x),
        y1 = std::max(y1, p.y);
    return {x0, y0, x1 - x0, y1 - y0};
}

cv::Rect expanded_box(const std::vector<cv::Point2f>& poly, double grow, int margin) {
    const cv::Rect2f b = bounds(poly);
    const double gx = b.width * grow + margin, gy = b.height * grow + margin;
    return cv::Rect(static_cast<int>(std::floor(b.x - gx)), static_cast<int>(std::floor(b.y - gy)),
                    static_cast<int>(std::ceil(b.width + 2 * gx)) + 1,
                    static_cast<int>(std::ceil(b.height + 2 * gy)) + 1);
}

}  // namespace

std::string_view to_string(RegionDescriptor d) {
    switch (d) {
        case RegionDescriptor::kSift:
            return "sift";
        case RegionDescriptor::kOrb:
            return "orb";
        case RegionDescriptor::kAkaze:
            return "akaze";
    }
    return "?";
}

bool parse_region_descriptor(std::string_view name, RegionDescriptor& out) {
    for (RegionDescriptor d :
         {RegionDescriptor::kSift, RegionDescriptor::kOrb, RegionDescriptor::kAkaze})
        if (name == to_string(d)) return out = d, true;
    return false;
}

std::string_view to_string(RegionState s) {
    return s == RegionState::kTracked ? "tracked" : "lost";
}

struct RegionTracker::Impl {
    struct Region {
        int id = 0;
        std::vector<cv::Point2f> kf_polygon;  // the marking frame's pixels
        double kf_area = 0;
        bool convex = false;
        detail::FeatureSet keyframe;
        std::vector<cv::Point2f> kf_track;  // corners and keypoints that LK follows
        RegionState state = RegionState::kTracked;
        cv::Matx33d homography = cv::Matx33d::eye();  // keyframe -> current frame
        std::vector<cv::Point2f> polygon;             // current, or last known while lost
        std::vector<cv::Point2f> rigid;               // the keyframe polygon through `homography`
        std::vector<cv::Point2f> kf_pts, cur_pts;     // features followed frame to frame
        std::vector<int> track_index;                 // each one's entry in kf_track
        int inliers = 0;
        int since_match = 0;
        bool force_match = true;  // the next frame is matched against the keyframe
        std::uint64_t mark_sequence = 0;
        hal::Nanos mark_capture_ns = 0;
    };

    explicit Impl(RegionTrackerParams params)
        : p(params),
          keyframe_detector(p.descriptor, p.detect_max_width, kKeyframeFeatures),
          frame_detector(p.descriptor, p.detect_max_width, kFrameFeatures),
          high_pass(kShadingBox),
          lk(kLk) {}

    bool plausible(const Region& r, const cv::Matx33d& h, cv::Size frame,
                   std::vector<cv::Point2f>& poly) const;
    bool propagate(Region& r, cv::Size frame);
    void build_pyramid(const hal::Frame& f, cv::Rect roi, detail::LkPyramid& pyr);
    void reserve_points(std::size_t n);
    const cv::Mat& full_gray();
    bool match(Region& r, const cv::Mat& gray, bool whole, const std::vector<cv::Point2f>& around);
    void reseed(Region& r, cv::Size frame, bool keep_followed);
    void bend(Region& r);

    RegionTrackerParams p;
    detail::FeatureDetector keyframe_detector, frame_detector;
    std::vector<Region> regions;
    // Propagation works in a window around the tracked regions: `window` of this
    // frame, `prev_window` of the previous one (the same rectangle while it holds them).
    const hal::Frame* current = nullptr;
    cv::Size last_size;
    cv::Rect window_rect, prev_window;
    cv::Mat gray, mask;
    bool gray_ready = false;
    // The propagation's own image pipeline, LK and RANSAC: OpenCV's allocate per call
    // (docs/regions.md "Speed"); these are sized once per frame size, then reused.
    detail::HighPassWindow high_pass;
    detail::LkPyramid pyramid, prev_pyramid;
    cv::Size reserved_size;
    detail::PyramidLk lk;
    detail::RansacHomography ransac;
    detail::FeatureSet whole_frame, window;
    bool whole_frame_ready = false;
    detail::KeyframeMatch matched;
    std::vector<cv::Point2f> lk_prev, lk_next, kept_kf, kept_cur, candidate;
    std::vector<int> kept_index;
    std::vector<cv::Point2f> offsets;
    std::vector<std::uint8_t> lk_status, inlier_mask, followed;
};

bool RegionTracker::Impl::plausible(const Region& r, const cv::Matx33d& h, cv::Size frame,
                                    std::vector<cv::Point2f>& poly) const {
    poly.clear();
    for (const cv::Point2f& v : r.kf_polygon) {
        const double w = h(2, 0) * v.x + h(2, 1) * v.y + h(2, 2);
        if (!(w > 1e-9)) return false;  // a vertex behind the view: a degenerate fit
        const double x = (h(0, 0) * v.x + h(0, 1) * v.y + h(0, 2)) / w,
                     y = (h(1, 0) * v.x + h(1, 1) * v.y + h(1, 2)) / w;
        if (!std::isfinite(x) || !std::isfinite(y)) return false;
        poly.emplace_back(static_cast<float>(x), static_cast<float>(y));
    }
    const double area = signed_area(poly);
    const double ratio = area / r.kf_area;  // negative: mirrored
    if (!(ratio > 1.0 / kMaxAreaRatio && ratio < kMaxAreaRatio)) return false;
    if (r.convex && !cv::isContourConvex(poly)) return false;
    const cv::Rect2f box = bounds(poly);
    const cv::Rect2f seen =
        box & cv::Rect2f(0, 0, static_cast<float>(frame.width), static_cast<float>(frame.height));
    return box.area() > 0 && seen.area() >= kMinVisible * box.area();
}

// Frames wider than kLkMaxWidth are followed at reduced size: the same texture scale
// for LK whatever the input, and a quarter of the work at 1080p. LK follows the texture,
// not the light: the endoscope carries its light, so shading moves with the camera and
// would drag the points (a high-pass image, HighPassWindow). The buffers are sized for
// the whole frame when its size changes, so a window of any size reuses them.
void RegionTracker::Impl::build_pyramid(const hal::Frame& f, cv::Rect roi, detail::LkPyramid& pyr) {
    const cv::Size size(f.format.width, f.format.height);
    if (size != reserved_size) {
        high_pass.reserve(size.width, size.height, lk_scale(size.width));
        const cv::Size lk_size = high_pass.scaled(size);
        pyramid.reserve(lk_size.width, lk_size.height, kLk);
        prev_pyramid.reserve(lk_size.width, lk_size.height, kLk);
        reserved_size = size;
    }
    high_pass.build(f, roi, pyr);
}

// The per-frame buffers for regions of up to n followed points (allocates, in mark()).
void RegionTracker::Impl::reserve_points(std::size_t n) {
    n = std::max(n, RegionEstimate::kMaxVertices);
    for (auto* v : {&lk_prev, &lk_next, &kept_kf, &kept_cur, &candidate, &offsets}) v->reserve(n);
    for (auto* v : {&lk_status, &inlier_mask, &followed}) v->reserve(n);
    kept_index.reserve(n);
}

const cv::Mat& RegionTracker::Impl::full_gray() {
    if (!gray_ready)
        to_gray(*current, cv::Rect(0, 0, current->format.width, current->format.height), gray);
    gray_ready = true;
    return gray;
}

bool RegionTracker::Impl::propagate(Region& r, cv::Size frame) {
    // Window coordinates at LK's scale, pixel centres kept: x' = (x - x0 + 0.5) s - 0.5.
    const float s = static_cast<float>(lk_scale(frame.width));
    const cv::Point2f origin(static_cast<float>(window_rect.x) - 0.5f + 0.5f / s,
                             static_cast<float>(window_rect.y) - 0.5f + 0.5f / s);
    lk_prev.clear();
    for (const cv::Point2f& q : r.cur_pts) lk_prev.push_back((q - origin) * s);
    lk_next.resize(lk_prev.size());
    lk_status.resize(lk_prev.size());
    lk.track(prev_pyramid, pyramid, lk_prev, lk_next, lk_status);
    kept_kf.clear();
    kept_cur.clear();
    kept_index.clear();
    for (std::size_t i = 0; i < lk_next.size(); ++i) {
        const cv::Point2f q = lk_next[i] / s + origin;
        if (!lk_status[i] || q.x < 0 || q.y < 0 || q.x > frame.width - 1 || q.y > frame.height - 1)
            continue;
        kept_kf.push_back(r.kf_pts[i]);
        kept_cur.push_back(q);
        kept_index.push_back(r.track_index[i]);
    }
    if (kept_kf.size() < static_cast<std::size_t>(std::max(4, p.min_inliers))) return false;
    inlier_mask.resize(kept_kf.size());
    ransac.set_threshold(p.ransac_px / s);
    cv::Matx33d h;
    if (!ransac.fit(kept_kf, kept_cur, h, inlier_mask)) return false;
    // The homography's inliers are followed. So is a point off it by up to a bend's
    // amount whose offset matches its neighbours' (a smooth bend moves a patch of
    // tissue together); a point alone in its offset is LK losing its texture: dropped.
    const double size = std::sqrt(std::abs(r.kf_area));
    const double bend_px = kBendFraction * size,
                 inv2s2 = 1.0 / (2 * kBendSigma * size * kBendSigma * size);
    const double tol = p.ransac_px / s;
    offsets.resize(kept_kf.size());
    for (std::size_t i = 0; i < kept_kf.size(); ++i) {
        const cv::Point2f& v = kept_kf[i];
        const double w = h(2, 0) * v.x + h(2, 1) * v.y + h(2, 2);
        offsets[i] = kept_cur[i] -
                     cv::Point2f(static_cast<float>((h(0, 0) * v.x + h(0, 1) * v.y + h(0, 2)) / w),
                                 static_cast<float>((h(1, 0) * v.x + h(1, 1) * v.y + h(1, 2)) / w));
    }
    r.kf_pts.clear();
    r.cur_pts.clear();
    r.track_index.clear();
    r.inliers = 0;
    for (std::size_t i = 0; i < kept_kf.size(); ++i) {
        bool keep = inlier_mask[i] != 0;
        if (!keep && p.bend && std::hypot(offsets[i].x, offsets[i].y) <= bend_px) {
            double sw = 0, mx = 0, my = 0;
            for (std::size_t j = 0; j < kept_kf.size(); ++j) {
                if (j == i || std::hypot(offsets[j].x, offsets[j].y) > bend_px) continue;
                const cv::Point2f d = kept_kf[j] - kept_kf[i];
                const double wt = std::exp(-(d.x * d.x + d.y * d.y) * inv2s2);
                sw += wt, mx += wt * offsets[j].x, my += wt * offsets[j].y;
            }
            keep = sw >= 1.0 && std::hypot(offsets[i].x - mx / sw, offsets[i].y - my / sw) <= tol;
        }
        if (!keep) continue;
        r.inliers += inlier_mask[i] ? 1 : 0;
        r.kf_pts.push_back(kept_kf[i]);
        r.cur_pts.push_back(kept_cur[i]);
        r.track_index.push_back(kept_index[i]);
    }
    // Most followed points must agree (with the homography, or with it and a smooth
    // bend): a motion too large for LK scatters them, and a homography fitted to the few
    // that happen to agree would be wrong.
    if (r.inliers < p.min_inliers ||
        static_cast<double>(r.kf_pts.size()) < kMinAgreeing * static_cast<double>(lk_next.size()) ||
        !plausible(r, h, frame, candidate))
        return false;
    r.homography = h;
    r.rigid = candidate;
    r.polygon = candidate;
    if (p.bend) bend(r);
    return true;
}

// Each vertex moved by the tissue's local motion: the followed points' offsets from the
// homography, fitted around the vertex by Gaussian-weighted least squares to a plane
// (offset + gradient, so a vertex beyond the points is extrapolated, not averaged) and
// evaluated at the vertex. Rigid motion leaves offsets of noise size: the outline stays
// the homography's. A pseudo-point of zero offset at the vertex damps the fit where few
// points are near.
void RegionTracker::Impl::bend(Region& r) {
    const double size = std::sqrt(std::abs(r.kf_area));
    const double inv2s2 = 1.0 / (2 * (kBendSigma * size) * (kBendSigma * size));
    const cv::Matx33d& h = r.homography;
    for (std::size_t k = 0; k < r.kf_polygon.size(); ++k) {
        const cv::Point2f v = r.kf_polygon[k];
        // Normal equations of [1, dx, dy] for the x and y offsets.
        cv::Matx33d a = cv::Matx33d::zeros();
        cv::Vec3d bx(0, 0, 0), by(0, 0, 0);
        const double prior = 0.5;
        a(0, 0) = prior;
        double total = 0;
        for (std::size_t i = 0; i < r.kf_pts.size(); ++i) {
            const cv::Point2f& p = r.kf_pts[i];
            const double ux = (p.x - v.x) / size, uy = (p.y - v.y) / size;
            const double wt =
                std::exp(-((p.x - v.x) * (p.x - v.x) + (p.y - v.y) * (p.y - v.y)) * inv2s2);
            if (wt < 1e-4) continue;
            const double w = h(2, 0) * p.x + h(2, 1) * p.y + h(2, 2);
            const double ox = r.cur_pts[i].x - (h(0, 0) * p.x + h(0, 1) * p.y + h(0, 2)) / w;
            const double oy = r.cur_pts[i].y - (h(1, 0) * p.x + h(1, 1) * p.y + h(1, 2)) / w;
            const cv::Vec3d f(1, ux, uy);
            a += wt * (f * f.t());
            bx += wt * ox * f;
            by += wt * oy * f;
            total += wt;
        }
        if (total < 3) continue;  // too few points near this vertex to say
        cv::Vec3d cx, cy;
        if (!cv::solve(a, bx, cx, cv::DECOMP_CHOLESKY) ||
            !cv::solve(a, by, cy, cv::DECOMP_CHOLESKY))
            continue;
        r.polygon[k] =
            r.rigid[k] + cv::Point2f(static_cast<float>(cx[0]), static_cast<float>(cy[0]));
    }
}

// Keyframe matching in a window around `around` (1.5x its size), or the whole frame.
// The result is left in `matched` and `candidate` (its polygon).
bool RegionTracker::Impl::match(Region& r, const cv::Mat& g, bool whole,
                                const std::vector<cv::Point2f>& around) {
    const detail::MatchParams mp{p.ratio, p.ransac_px * frame_detector.pixel_size(g.cols),
                                 p.min_inliers};
    detail::FeatureSet* features = &whole_frame;
    if (whole) {
        if (!whole_frame_ready)
            frame_detector.detect(g, cv::Rect(0, 0, g.cols, g.rows), cv::Mat(), whole_frame);
        whole_frame_ready = true;
    } else {
        frame_detector.detect(g, expanded_box(around, 0.25, 16), cv::Mat(), window);
        features = &window;
    }
    return detail::match_keyframe(r.keyframe, *features, frame_detector.norm(), mp, matched) &&
           plausible(r, matched.homography, g.size(), candidate);
}

void RegionTracker::Impl::reseed(Region& r, cv::Size frame, bool keep_followed) {
    // The keyframe's points through the region's homography: points that left the
    // picture and came back are followed again. Without keep_followed every point is
    // put back (the frame-to-frame drift of single points is dropped); with it, points
    // still followed keep their positions (and the tissue's bend), the lost ones return.
    const cv::Matx33d& h = r.homography;
    followed.assign(r.kf_track.size(), 0);
    if (keep_followed) {
        for (const int j : r.track_index) followed[static_cast<std::size_t>(j)] = 1;
    } else {
        r.kf_pts.clear();
        r.cur_pts.clear();
        r.track_index.clear();
    }
    for (std::size_t j = 0; j < r.kf_track.size(); ++j) {
        if (followed[j]) continue;
        const cv::Point2f& v = r.kf_track[j];
        const double w = h(2, 0) * v.x + h(2, 1) * v.y + h(2, 2);
        const double x = (h(0, 0) * v.x + h(0, 1) * v.y + h(0, 2)) / w,
                     y = (h(1, 0) * v.x + h(1, 1) * v.y + h(1, 2)) / w;
        if (!(x >= 0 && y >= 0 && x <= frame.width - 1 && y <= frame.height - 1)) continue;
        r.kf_pts.push_back(v);
        r.cur_pts.emplace_back(static_cast<float>(x), static_cast<float>(y));
        r.track_index.push_back(static_cast<int>(j));
    }
}

RegionTracker::RegionTracker(RegionTrackerParams params) : impl_(std::make_unique<Impl>(params)) {}
RegionTracker::~RegionTracker() = default;
const RegionTrackerParams& RegionTracker::params() const {
    return impl_->p;
}
std::size_t RegionTracker::size() const {
    return impl_->regions.size();
}

bool RegionTracker::mark(int id, std::span<const Point2> polygon, const hal::Frame& frame,
                         std::string& error) {
    Impl& m = *impl_;
    const std::string name = "region " + std::to_string(id);
    if (polygon.size() < 3 || polygon.size() > RegionEstimate::kMaxVertices) {
        error = name + ": a polygon needs 3 to " + std::to_string(RegionEstimate::kMaxVertices) +
                " vertices, got " + std::to_string(polygon.size());
        return false;
    }
    if (!supported(frame)) {
        error = name + ": unsupported pixel format " +
                std::string(hal::to_string(frame.format.pixel_format));
        return false;
    }
    m.current = &frame;
    m.gray_ready = false;
    const cv::Mat& g = m.full_gray();
    Impl::Region r;
    r.id = id;
    for (const Point2& v : polygon) {
        if (!std::isfinite(v.x) || !std::isfinite(v.y)) {
            error = name + ": vertex coordinates must be finite numbers";
            return false;
        }
        r.kf_polygon.emplace_back(static_cast<float>(v.x), static_cast<float>(v.y));
    }
    r.kf_area = signed_area(r.kf_polygon);
    r.convex = cv::isContourConvex(r.kf_polygon);
    const cv::Rect inside = expanded_box(r.kf_polygon, 0, 0) & cv::Rect(0, 0, g.cols, g.rows);
    if (std::abs(r.kf_area) < 64 || inside.area() < 64) {
        error = name + ": the polygon is degenerate (area " + std::to_string(std::abs(r.kf_area)) +
                " px) or outside the " + std::to_string(g.cols) + "x" + std::to_string(g.rows) +
                " frame";
        return false;
    }
    auto it = std::find_if(m.regions.begin(), m.regions.end(),
                           [id](const Impl::Region& x) { return x.id == id; });
    if (it == m.regions.end() && m.regions.size() >= kMaxRegions) {
        error = name + ": at most " + std::to_string(kMaxRegions) + " regions are tracked at once";
        return false;
    }
    // The mask, with a margin of context around it so descriptors near the outline see
    // their neighbourhood; features themselves only inside (the book's region mask).
    const cv::Rect roi = expanded_box(r.kf_polygon, 0, 32) & cv::Rect(0, 0, g.cols, g.rows);
    m.mask.create(roi.size(), CV_8UC1);
    m.mask.setTo(0);
    std::vector<cv::Point> outline;
    for (const cv::Point2f& v : r.kf_polygon)
        outline.emplace_back(cvRound(v.x - roi.x), cvRound(v.y - roi.y));
    cv::fillPoly(m.mask, std::vector<std::vector<cv::Point>>{outline}, cv::Scalar(255));
    m.keyframe_detector.detect(g, roi, m.mask, r.keyframe);
    if (r.keyframe.keypoints.size() < static_cast<std::size_t>(std::max(4, m.p.min_inliers))) {
        error = name + ": only " + std::to_string(r.keyframe.keypoints.size()) + " " +
                std::string(to_string(m.p.descriptor)) + " features inside the polygon (need " +
                std::to_string(std::max(4, m.p.min_inliers)) +
                "): mark a larger or more textured region";
        return false;
    }
    // LK follows Shi-Tomasi corners spread over the region: more points than a small
    // region has descriptors, and points LK locates well. Their number bounds its cost.
    cv::goodFeaturesToTrack(g(roi), r.kf_track, kTrackCorners, 0.005,
                            std::max(4.0, std::sqrt(std::abs(r.kf_area)) / 20), m.mask, 5);
    for (cv::Point2f& c : r.kf_track)
        c += cv::Point2f(static_cast<float>(roi.x), static_cast<float>(roi.y));
    if (r.kf_track.size() < static_cast<std::size_t>(m.p.min_inliers))
        for (const cv::KeyPoint& k : r.keyframe.keypoints) r.kf_track.push_back(k.pt);
    // Propagation's buffers, sized once: it allocates nothing per frame.
    const std::size_t points = r.kf_track.size();
    for (auto* v : {&r.kf_pts, &r.cur_pts}) v->reserve(points);
    for (auto* v : {&r.polygon, &r.rigid}) v->reserve(RegionEstimate::kMaxVertices);
    r.track_index.reserve(points);
    m.reserve_points(points);
    r.kf_pts = r.kf_track;
    r.cur_pts = r.kf_pts;
    r.track_index.resize(r.kf_track.size());
    r.polygon = r.kf_polygon;
    r.rigid = r.kf_polygon;
    for (std::size_t j = 0; j < r.kf_track.size(); ++j) r.track_index[j] = static_cast<int>(j);
    r.inliers = static_cast<int>(r.kf_pts.size());
    r.mark_sequence = frame.sequence;
    r.mark_capture_ns = frame.capture_ns;
    // The next frame propagates from this one, over a window holding this region too.
    const cv::Rect frame_rect(0, 0, g.cols, g.rows);
    if (m.last_size != g.size()) m.prev_window = cv::Rect();
    m.last_size = g.size();
    m.prev_window = (m.prev_window | expanded_box(r.kf_polygon, 0.25, 48)) & frame_rect;
    if (m.p.propagate) m.build_pyramid(frame, m.prev_window, m.prev_pyramid);
    if (it != m.regions.end())
        *it = std::move(r);
    else
        m.regions.push_back(std::move(r));
    m.current = nullptr;
    return true;
}

std::size_t RegionTracker::track(const hal::Frame& frame, std::span<RegionEstimate> out) {
    Impl& m = *impl_;
    m.current = &frame;
    m.gray_ready = false;
    m.whole_frame_ready = false;
    const bool readable = supported(frame);
    const cv::Size size = readable ? cv::Size(frame.format.width, frame.format.height) : cv::Size();
    const bool resized = !readable || size != m.last_size;
    m.last_size = size;
    const bool can_propagate = readable && m.p.propagate && !resized && !m.prev_window.empty();
    if (can_propagate) {
        m.window_rect = m.prev_window;
        m.build_pyramid(frame, m.window_rect, m.pyramid);
    }
    std::size_t n = 0;
    for (Impl::Region& r : m.regions) {
        bool found = false, keyframe = false;
        if (!readable) {
            found = false;
        } else if (frame.sequence == r.mark_sequence && frame.capture_ns == r.mark_capture_ns) {
            found = true;  // the marking frame itself
        } else {
            const bool was_tracked = r.state == RegionState::kTracked && !resized;
            if (can_propagate && was_tracked && r.cur_pts.size() >= 4) found = m.propagate(r, size);
            // Points lost to LK are put back through the fitted homography before too
            // few are left (those that re-entered the picture too).
            if (found && 2 * r.cur_pts.size() < r.kf_track.size()) m.reseed(r, size, true);
            ++r.since_match;
            const bool due = m.p.redetect_interval > 0 && r.since_match >= m.p.redetect_interval;
            if (!m.p.propagate || r.force_match || !found || due || resized) {
                // Drift correction near where the region is; recovery over the whole frame.
                const bool near = was_tracked && (found || !m.p.propagate);
                const cv::Mat& g = m.full_gray();
                bool ok = m.match(r, g, !near, r.polygon);
                if (!ok && near && !found) ok = m.match(r, g, true, r.polygon);
                if (ok) {
                    r.since_match = 0;
                    // Propagation that agrees with the keyframe is kept (many more points,
                    // sub-pixel, and the tissue's bend); one that has drifted further is
                    // replaced. Two rigid fits to bending tissue differ by up to the bend
                    // itself, which is not drift.
                    const double tolerance = kAgreePx * m.frame_detector.pixel_size(size.width) +
                                             mean_distance(r.polygon, r.rigid);
                    // A match at the bare minimum of inliers is as likely wrong as the
                    // drift it would correct: only a clear one overrides a propagation.
                    const bool replace = !found || r.force_match ||
                                         (mean_distance(m.candidate, r.rigid) > tolerance &&
                                          m.matched.inliers >= 2 * m.p.min_inliers);
                    if (replace) {
                        r.homography = m.matched.homography;
                        r.polygon = m.candidate;
                        r.rigid = m.candidate;
                        r.inliers = m.matched.inliers;
                        keyframe = true;
                    }
                    m.reseed(r, size, !replace);
                    r.force_match = false;
                }
                found = found || ok;
            }
        }
        if (found) {
            r.state = RegionState::kTracked;
        } else {
            r.state = RegionState::kLost;
            r.inliers = 0;
            r.cur_pts.clear();
            r.kf_pts.clear();
            r.track_index.clear();
        }
        if (n >= out.size()) continue;
        RegionEstimate& e = out[n++];
        e.id = r.id;
        e.state = r.state;
        e.inliers = r.inliers;
        e.keyframe_match = keyframe;
        e.vertices = r.polygon.size();
        for (std::size_t i = 0; i < e.vertices; ++i) {
            e.polygon[i] = {r.polygon[i].x, r.polygon[i].y};
            e.marked[i] = {r.kf_polygon[i].x, r.kf_polygon[i].y};
        }
        for (int i = 0; i < 9; ++i) e.homography[static_cast<std::size_t>(i)] = r.homography.val[i];
    }
    // The next frame's window: kept while it holds every tracked region with room to
    // move, else redrawn around them.
    cv::Rect tight, next;
    for (const Impl::Region& r : m.regions) {
        if (r.state != RegionState::kTracked) continue;
        tight |= expanded_box(r.polygon, 0, 16);
        next |= expanded_box(r.polygon, 0.25, 48);
    }
    const cv::Rect frame_rect(0, 0, size.width, size.height);
    tight &= frame_rect;
    next &= frame_rect;
    if (!m.p.propagate || next.empty()) {
        m.prev_window = cv::Rect();
    } else if (can_propagate && (tight & m.window_rect) == tight) {
        std::swap(m.pyramid, m.prev_pyramid);  // the same window: this frame's pyramid serves
    } else {
        m.prev_window = next;
        m.build_pyramid(frame, next, m.prev_pyramid);
    }
    m.current = nullptr;
    return n;
}

}  // namespace endotower::vision
