#include "endotower/vision/strip_marker_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace endotower::vision {

namespace {

constexpr int kMaxParts = 24;  // the largest tool parts considered (pairs: 276)

struct Part {
    int label = 0, area = 0;
    double mean = 0;      // grey level
    bool leaves = false;  // reaches the picture's edge or the unlit rim: the shaft side
    cv::Rect box;
    std::vector<cv::Point> hull;
};

struct Strip {
    int part_a = 0, part_b = 0;
    Point2 a, b, c, d, e, v;
    double diameter_px = 0;
    double width_a = 0, width_b = 0, mid_a = 0, mid_b = 0;  // M and E's offset per side
};

// Where the line origin + t dir crosses the convex polygon: [t0, t1]; false if it misses.
bool chord(const std::vector<cv::Point>& poly, Point2 o, Point2 dir, double& t0, double& t1) {
    t0 = 1e300, t1 = -1e300;
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
        const cv::Point p = poly[i], q = poly[(i + 1) % n];
        const double ex = q.x - p.x, ey = q.y - p.y;
        const double den = dir.x * ey - dir.y * ex;
        if (std::abs(den) < 1e-12) continue;
        const double wx = p.x - o.x, wy = p.y - o.y;
        const double t = (wx * ey - wy * ex) / den;        // along dir
        const double s = (wx * dir.y - wy * dir.x) / den;  // along the edge
        if (s < -1e-9 || s > 1 + 1e-9) continue;
        t0 = std::min(t0, t), t1 = std::max(t1, t);
    }
    return t1 > t0;
}

// Bilinear sample of an 8-bit image (clamped to its border).
double sample(const cv::Mat& img, double x, double y) {
    x = std::clamp(x, 0.0, img.cols - 1.001), y = std::clamp(y, 0.0, img.rows - 1.001);
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
    const double fx = x - x0, fy = y - y0;
    const std::uint8_t* r0 = img.ptr<std::uint8_t>(y0);
    const std::uint8_t* r1 = img.ptr<std::uint8_t>(y0 + 1);
    return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) +
           fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

// One silhouette edge of the shaft on the ray origin + t dir (t >= 0 outwards from
// the axis), near the thresholded edge `at`. Under the scope's coaxial light the limb
// of a cylinder darkens to a rim darker than its surroundings; the threshold stops
// short of it. With a rim (the minimum near `at` 8 grey levels below the background
// outside, the median of 9 samples past it) the edge is where the profile climbs
// back half-way from the rim to the background; without one (a background darker
// than the limb) where it falls half-way from the metal (at `at` - 3 px) to the
// background. Linear interpolation between 0.5 px samples. False when neither.
bool silhouette_edge(const cv::Mat& img, Point2 o, Point2 dir, double at, double& out) {
    constexpr double kStep = 0.5;
    const auto p = [&](double t) { return sample(img, o.x + t * dir.x, o.y + t * dir.y); };
    const double reach = std::max(6.0, 0.3 * at);
    std::array<double, 9> outside{};
    for (int k = 0; k < 9; ++k) outside[k] = p(at + reach + 1 + k);
    std::nth_element(outside.begin(), outside.begin() + 4, outside.end());
    const double bg = outside[4];
    double t_min = at, p_min = 1e9;
    for (double t = std::max(0.0, at - 3); t <= at + reach; t += kStep)
        if (const double v = p(t); v < p_min) p_min = v, t_min = t;
    if (bg - p_min >= 8) {
        const double level = 0.5 * (p_min + bg);
        double prev = p_min;
        for (double t = t_min + kStep; t <= at + reach + 1; t += kStep) {
            const double v = p(t);
            if (v >= level) {
                out = t - kStep * (v - level) / (v - prev);
                return true;
            }
            prev = v;
        }
        return false;
    }
    const double metal = p(std::max(0.0, at - 3));
    if (metal - bg < 8) return false;
    const double level = 0.5 * (metal + bg);
    double prev = metal;
    for (double t = std::max(0.0, at - 3) + kStep; t <= at + reach + 1; t += kStep) {
        const double v = p(t);
        if (v <= level) {
            out = t - kStep * (level - v) / (prev - v);
            return true;
        }
        prev = v;
    }
    return false;
}

// The strip's middle along the axis, measured near a silhouette, on the line
// o + t u (t from t0 to t1, metal at both ends, the strip between): the midpoint of
// the two places where the profile crosses half-way between the metal at that end
// and the darkest paint. False when either crossing is missing.
bool strip_middle(const cv::Mat& img, Point2 o, Point2 u, double t0, double t1, double& out) {
    constexpr double kStep = 0.5;
    const auto p = [&](double t) { return sample(img, o.x + t * u.x, o.y + t * u.y); };
    double dark = 1e9;
    for (double t = t0; t <= t1; t += kStep) dark = std::min(dark, p(t));
    const double ma = p(t0), mb = p(t1);
    if (ma - dark < 12 || mb - dark < 12) return false;
    const double la = 0.5 * (ma + dark), lb = 0.5 * (mb + dark);
    double ta = 0, tb = 0, prev = ma;
    bool fa = false, fb = false;
    for (double t = t0 + kStep; t <= t1; t += kStep) {
        const double v = p(t);
        if (v < la) {
            ta = t - kStep * (la - v) / (prev - v), fa = true;
            break;
        }
        prev = v;
    }
    prev = mb;
    for (double t = t1 - kStep; t >= t0; t -= kStep) {
        const double v = p(t);
        if (v < lb) {
            tb = t + kStep * (lb - v) / (prev - v), fb = true;
            break;
        }
        prev = v;
    }
    if (!fa || !fb || !(tb > ta)) return false;
    out = 0.5 * (ta + tb);
    return true;
}

}  // namespace

struct StripMarkerTracker::Work {
    cv::Mat gray, opened, local_max, bright, labels, stats, centroids, hull_mask;
    cv::Mat thin_element, band_element, window_element;
    std::vector<Part> parts;
    std::vector<cv::Point> points, pair_hull;
    std::vector<Strip> strips;
    std::vector<int> group;
};

StripMarkerTracker::StripMarkerTracker(StripMarkerParams params) : params_(params) {}
StripMarkerTracker::~StripMarkerTracker() = default;
StripMarkerTracker::StripMarkerTracker(StripMarkerTracker&&) noexcept = default;

void StripMarkerTracker::set_calibration(const calibration::SeparationTable& table,
                                         const PinholeCamera& camera,
                                         std::function<Point2(Point2)> undistort) {
    table_ = table;
    camera_ = camera;
    undistort_ = std::move(undistort);
}

void StripMarkerTracker::configure(const hal::FrameFormat& format) {
    work_ = std::make_unique<Work>();
    Work& w = *work_;
    const cv::Size size(format.width, format.height);
    for (cv::Mat* m : {&w.gray, &w.opened, &w.local_max, &w.bright, &w.hull_mask})
        m->create(size, CV_8UC1);
    w.labels.create(size, CV_32S);
    w.hull_mask.setTo(0);
    const auto odd = [](double v) { return std::max(3, static_cast<int>(std::lround(v)) | 1); };
    const int band = odd(params_.min_band_fraction * format.height);
    const int window = odd(params_.window_fraction * format.height);
    w.thin_element = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(band, band));
    w.band_element = w.thin_element;
    w.window_element = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(window, window));
    w.parts.resize(kMaxParts);
    for (Part& p : w.parts) p.hull.reserve(256);
    w.points.reserve(4096);
    w.pair_hull.reserve(512);
    w.strips.reserve(kMaxParts * 2);
    w.group.resize(kMaxParts);
}

double StripMarkerTracker::undistorted_diameter(Point2 e, Point2 a, Point2 b,
                                                double diameter) const {
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (!undistort_ || !(len > 0)) return diameter;
    const Point2 across{(b.x - a.x) / len, (b.y - a.y) / len};
    const double h = diameter / 2;
    const Point2 p = undistort_({e.x - h * across.x, e.y - h * across.y});
    const Point2 q = undistort_({e.x + h * across.x, e.y + h * across.y});
    return std::hypot(q.x - p.x, q.y - p.y);
}

void StripMarkerTracker::locate(StripMarker& m) const {
    m.located = false;
    if (!undistort_ || table_.distances_mm.size() < 2 || !(params_.diameter_mm > 0) ||
        !(camera_.fx > 0))
        return;
    // M across the axis, both ends undistorted: the table holds undistorted separations.
    const double len = std::hypot(m.b.x - m.a.x, m.b.y - m.a.y);
    if (!(len > 0)) return;
    const Point2 across{(m.b.x - m.a.x) / len, (m.b.y - m.a.y) / len};
    const double h = m.diameter_px / 2;
    const Point2 p = undistort_({m.e.x - h * across.x, m.e.y - h * across.y});
    const Point2 q = undistort_({m.e.x + h * across.x, m.e.y + h * across.y});
    const Point2 e = undistort_(m.e);
    double diameter = std::hypot(q.x - p.x, q.y - p.y);
    if (!(diameter > 0)) return;
    // The table's dots lie in a plane facing the camera; the shaft's round section
    // off the optical axis (angle t, tan t = rho / f) images wider: by 1 / cos^2 t
    // along the radial direction, not at all across it (psi: M's angle to the radial).
    const double rx = e.x - camera_.cx, ry = e.y - camera_.cy, rho = std::hypot(rx, ry);
    if (rho > 0) {
        const double cos2t = 1 / (1 + (rho / camera_.fx) * (rho / camera_.fx));
        const double cpsi = (across.x * rx + across.y * ry) / rho;
        diameter /= std::sqrt(cpsi * cpsi / cos2t + (1 - cpsi * cpsi));
    }
    // The tool's diameter D shows as many pixels as a separation of marker_mm * M / D.
    m.depth_mm = table_.depth_for_separation(table_.marker_mm * diameter / params_.diameter_mm);
    m.depth_pinhole_mm = camera_.fx * params_.diameter_mm / diameter;
    if (!(m.depth_mm > 0)) return;
    m.e_mm = {table_.to_mm(e.x, camera_.cx, m.depth_mm), table_.to_mm(e.y, camera_.cy, m.depth_mm),
              m.depth_mm};
    m.located = true;
}

std::size_t StripMarkerTracker::track(const hal::Frame& frame,
                                      std::span<StripMarker, kMaxMarkers> out) {
    if (!work_ || !frame.data) return 0;
    Work& w = *work_;
    const hal::FrameFormat& f = frame.format;
    if (f.width != w.gray.cols || f.height != w.gray.rows) return 0;
    if (f.pixel_format == hal::PixelFormat::kBgr24) {
        const cv::Mat bgr(f.height, f.width, CV_8UC3, frame.data,
                          static_cast<std::size_t>(f.stride));
        cv::cvtColor(bgr, w.gray, cv::COLOR_BGR2GRAY);
    } else if (f.pixel_format == hal::PixelFormat::kGray8) {
        cv::Mat(f.height, f.width, CV_8UC1, frame.data, static_cast<std::size_t>(f.stride))
            .copyTo(w.gray);
    } else {
        return 0;
    }

    // 1. Tool parts: brighter than the background (the book's black paper, lit
    // tissue farther from the light than the tool). Thin bright lines (the grid,
    // glints) are removed first by a grey opening. The background level is the median
    // of the lit picture (the tool covers the smaller part of it).
    cv::morphologyEx(w.gray, w.opened, cv::MORPH_OPEN, w.thin_element);
    cv::dilate(w.opened, w.local_max, w.window_element);
    const int rows = f.height, cols = f.width;
    std::array<int, 256> hist{};
    long lit = 0;
    for (int y = 0; y < rows; y += 2) {
        const std::uint8_t* o = w.opened.ptr<std::uint8_t>(y);
        for (int x = 0; x < cols; x += 2)
            if (o[x] >= params_.min_level) ++hist[o[x]], ++lit;
    }
    if (lit == 0) return 0;
    int median = 0;
    for (long acc = 0; median < 255 && (acc += hist[median]) < lit / 2;) ++median;
    const double level =
        std::max(median + 0.5 * params_.min_contrast, median * (1 + params_.bright_margin));
    if (level >= 255) return 0;
    cv::threshold(w.opened, w.bright, level, 255, cv::THRESH_BINARY);
    cv::morphologyEx(w.bright, w.bright, cv::MORPH_OPEN, w.band_element);
    const int n =
        cv::connectedComponentsWithStats(w.bright, w.labels, w.stats, w.centroids, 8, CV_32S);
    const int band = w.band_element.rows;
    std::size_t nparts = 0;
    {
        // The largest parts first.
        w.points.clear();
        for (int i = 1; i < n; ++i)
            if (w.stats.at<int>(i, cv::CC_STAT_AREA) >= band * band)
                w.points.push_back({w.stats.at<int>(i, cv::CC_STAT_AREA), i});
        std::sort(w.points.begin(), w.points.end(),
                  [](cv::Point a, cv::Point b) { return a.x > b.x; });
        nparts = std::min<std::size_t>(w.points.size(), kMaxParts);
        for (std::size_t k = 0; k < nparts; ++k) {
            Part& p = w.parts[k];
            p.label = w.points[k].y;
            p.area = w.points[k].x;
            p.box = {w.stats.at<int>(p.label, cv::CC_STAT_LEFT),
                     w.stats.at<int>(p.label, cv::CC_STAT_TOP),
                     w.stats.at<int>(p.label, cv::CC_STAT_WIDTH),
                     w.stats.at<int>(p.label, cv::CC_STAT_HEIGHT)};
        }
        for (std::size_t k = 0; k < nparts; ++k) {
            Part& p = w.parts[k];
            w.points.clear();
            double sum = 0;
            // Boundary pixels are enough for the hull.
            for (int y = p.box.y; y < p.box.y + p.box.height; ++y) {
                const int* l = w.labels.ptr<int>(y);
                const int* up = y > 0 ? w.labels.ptr<int>(y - 1) : nullptr;
                const int* dn = y + 1 < rows ? w.labels.ptr<int>(y + 1) : nullptr;
                for (int x = p.box.x; x < p.box.x + p.box.width; ++x) {
                    if (l[x] != p.label) continue;
                    sum += w.gray.ptr<std::uint8_t>(y)[x];
                    if (!up || !dn || x == 0 || x + 1 == cols || up[x] != p.label ||
                        dn[x] != p.label || l[x - 1] != p.label || l[x + 1] != p.label)
                        w.points.push_back({x, y});
                }
            }
            cv::convexHull(w.points, p.hull);
            p.mean = sum / p.area;
            // The shaft leaves the picture: the part comes within `band` px of the
            // image border or of unlit pixels (outside the scope's field of view).
            const cv::Rect near = cv::Rect(p.box.x - band, p.box.y - band, p.box.width + 2 * band,
                                           p.box.height + 2 * band);
            const cv::Rect clipped = near & cv::Rect(0, 0, cols, rows);
            p.leaves = clipped != near;
            double unlit = 255;
            if (!p.leaves) cv::minMaxLoc(w.gray(clipped), &unlit);
            p.leaves = p.leaves || unlit <= params_.unlit_level;
        }
        // A wide uniform part shows no contrast inside: its hull is the part.
        for (std::size_t k = 0; k < nparts; ++k)
            cv::fillConvexPoly(w.labels, w.parts[k].hull, cv::Scalar(w.parts[k].label));
    }

    // 2. Strips: the dark gap between two parts.
    w.strips.clear();
    const int window = w.window_element.rows;
    for (std::size_t i = 0; i < nparts; ++i) {
        for (std::size_t j = i + 1; j < nparts; ++j) {
            const Part &pi = w.parts[i], &pj = w.parts[j];
            const int gx = std::max(
                {0, pj.box.x - (pi.box.x + pi.box.width), pi.box.x - (pj.box.x + pj.box.width)});
            const int gy = std::max(
                {0, pj.box.y - (pi.box.y + pi.box.height), pi.box.y - (pj.box.y + pj.box.height)});
            if (std::max(gx, gy) > window) continue;
            w.points.assign(pi.hull.begin(), pi.hull.end());
            w.points.insert(w.points.end(), pj.hull.begin(), pj.hull.end());
            cv::convexHull(w.points, w.pair_hull);
            const cv::Rect box = cv::boundingRect(w.pair_hull) & cv::Rect(0, 0, cols, rows);
            cv::Mat roi = w.hull_mask(box);
            cv::fillConvexPoly(w.hull_mask, w.pair_hull, 255);
            long between = 0, dark = 0, foreign = 0;
            double sx = 0, sy = 0, level = 0;
            for (int y = box.y; y < box.y + box.height; ++y) {
                const std::uint8_t* h = w.hull_mask.ptr<std::uint8_t>(y);
                const int* l = w.labels.ptr<int>(y);
                const std::uint8_t* g = w.gray.ptr<std::uint8_t>(y);
                const std::uint8_t* hi = w.local_max.ptr<std::uint8_t>(y);
                for (int x = box.x; x < box.x + box.width; ++x) {
                    if (!h[x]) continue;
                    if (l[x] == pi.label || l[x] == pj.label) continue;
                    if (l[x] != 0) {
                        ++foreign;
                        continue;
                    }
                    ++between;
                    sx += x, sy += y;
                    level += g[x];
                    if (g[x] < params_.dark_ratio * hi[x]) ++dark;
                }
            }
            roi.setTo(0);
            const double smaller = std::min(pi.area, pj.area);
            if (between < std::max<double>(band * band, 0.1 * smaller) || between > 3 * smaller)
                continue;
            if (dark < params_.dark_fill * between || foreign > 0.05 * between) continue;
            // Black paint: much darker than the metal on both sides, not a shading dip.
            if (level / between > params_.dark_ratio * std::min(pi.mean, pj.mean)) continue;

            // 3. Blob analysis: E, the axis from part to part, the trapezoid.
            Strip s;
            s.part_a = static_cast<int>(i), s.part_b = static_cast<int>(j);
            s.e = {sx / between, sy / between};
            const double ux =
                w.centroids.at<double>(pj.label, 0) - w.centroids.at<double>(pi.label, 0);
            const double uy =
                w.centroids.at<double>(pj.label, 1) - w.centroids.at<double>(pi.label, 1);
            const double ul = std::hypot(ux, uy);
            if (!(ul > 0)) continue;
            const Point2 u{ux / ul, uy / ul}, v{-u.y, u.x};
            double t0, t1;
            if (!chord(w.pair_hull, s.e, v, t0, t1)) continue;
            s.diameter_px = t1 - t0;
            // The strip's extent along u: where the parts' hulls end towards E.
            double a0, a1, b0, b1;
            const bool ha = chord(pi.hull, s.e, u, a0, a1), hb = chord(pj.hull, s.e, u, b0, b1);
            const double lo = ha ? a1 : -0.25 * s.diameter_px, hi = hb ? b0 : 0.25 * s.diameter_px;
            if (!(hi > lo)) continue;
            // The strip is as wide as the tool: the parts' widths across u agree with M.
            double c0, c1, d0, d1;
            const Point2 pa{s.e.x + lo * u.x, s.e.y + lo * u.y},
                pb{s.e.x + hi * u.x, s.e.y + hi * u.y};
            if (!chord(w.pair_hull, pa, v, c0, c1) || !chord(w.pair_hull, pb, v, d0, d1)) continue;
            s.a = {pa.x + c0 * v.x, pa.y + c0 * v.y};
            s.b = {pa.x + c1 * v.x, pa.y + c1 * v.y};
            s.c = {pb.x + d1 * v.x, pb.y + d1 * v.y};
            s.d = {pb.x + d0 * v.x, pb.y + d0 * v.y};
            // M and E across the axis from the metal's silhouettes just outside the strip
            // on both sides (the black paint need not stand out from a dark
            // background): M is the mean of the two widths, the trapezoid's mid-line.
            const double inset = std::max(2.0, 0.15 * (hi - lo));
            const Point2 qa{s.e.x + (lo - inset) * u.x, s.e.y + (lo - inset) * u.y},
                qb{s.e.x + (hi + inset) * u.x, s.e.y + (hi + inset) * u.y};
            const Point2 nv{-v.x, -v.y};
            // A bright line lying along a profile (the chart's grid, a glint) raises its
            // background level past anything the limb reaches: profiles moved along the
            // shaft, away from the strip and inside the part, stand in for it.
            const auto silhouettes = [&](double t, double step, double end, double c_lo,
                                         double c_hi, double& l, double& r) {
                for (int k = 0; k < 4; ++k, t += step) {
                    if ((step < 0 && t < end) || (step > 0 && t > end)) break;
                    const Point2 q{s.e.x + t * u.x, s.e.y + t * u.y};
                    if (silhouette_edge(w.gray, q, nv, -c_lo, l) &&
                        silhouette_edge(w.gray, q, v, c_hi, r))
                        return;
                }
                l = -c_lo, r = c_hi;
            };
            const double shift = 0.1 * (c1 - c0);
            double la = 0, ra = 0, lb = 0, rb = 0;
            silhouettes(lo - inset, -shift, ha ? a0 + 2 : lo - inset, c0, c1, la, ra);
            silhouettes(hi + inset, shift, hb ? b1 - 2 : hi + inset, d0, d1, lb, rb);
            s.a = {qa.x - la * v.x, qa.y - la * v.y};
            s.b = {qa.x + ra * v.x, qa.y + ra * v.y};
            s.c = {qb.x + rb * v.x, qb.y + rb * v.y};
            s.d = {qb.x - lb * v.x, qb.y - lb * v.y};
            // A rounded head, a shadow or a partly hidden part only narrows a side, so
            // the wider side is the tool (AB and CD differ by the perspective across
            // one strip, a few percent at most).
            const bool wide_a = la + ra >= lb + rb;
            s.diameter_px = wide_a ? la + ra : lb + rb;
            const double mid = wide_a ? 0.5 * (ra - la) : 0.5 * (rb - lb);
            s.width_a = la + ra, s.width_b = lb + rb, s.mid_a = 0.5 * (ra - la),
            s.mid_b = 0.5 * (rb - lb);
            s.v = v;
            s.e = {s.e.x + mid * v.x, s.e.y + mid * v.y};
            // Along the axis: the strip's rings image as ellipses whose front arcs are
            // displaced along the axis when the shaft leans towards or away from the
            // camera, by D sqrt(1 - xi^2) at xi radii off the midline; the rings' centres
            // (and E) are where that displacement is 0. The strip's middle measured on
            // the midline and at xi = +-0.8 gives D and the true middle.
            const double len = hi - lo, from = lo - 0.5 * len - 2, to = hi + 0.5 * len + 2;
            const double off = 0.8 * 0.5 * s.diameter_px;
            double mc, m0, m1;
            const Point2 o0{s.e.x - off * v.x, s.e.y - off * v.y},
                o1{s.e.x + off * v.x, s.e.y + off * v.y};
            if (strip_middle(w.gray, s.e, u, from, to, mc) &&
                strip_middle(w.gray, o0, u, from, to, m0) &&
                strip_middle(w.gray, o1, u, from, to, m1)) {
                const double side = 0.5 * (m0 + m1), d = (mc - side) / (1 - 0.6);
                const double along = mc - d;
                s.e = {s.e.x + along * u.x, s.e.y + along * u.y};
            }
            if (s.diameter_px < band || (hi - lo) > 3 * s.diameter_px) continue;
            w.strips.push_back(s);
        }
    }

    // 4. Strips sharing a part are one tool's; per tool the smallest M is nearest the tip.
    for (std::size_t k = 0; k < nparts; ++k) w.group[k] = static_cast<int>(k);
    const auto root = [&](int k) {
        while (w.group[k] != k) k = w.group[k] = w.group[w.group[k]];
        return k;
    };
    for (const Strip& s : w.strips) w.group[root(s.part_a)] = root(s.part_b);
    std::size_t found = 0;
    std::array<int, kMaxMarkers> roots{};
    for (std::size_t k = 0; k < w.strips.size() && found < out.size(); ++k) {
        const int r = root(w.strips[k].part_a);
        bool seen = false;
        for (std::size_t m = 0; m < found; ++m) seen = seen || roots[m] == r;
        if (seen) continue;
        // The nearest strip to the tip: when exactly one of the tool's parts leaves the
        // picture, that is the shaft and the strip farthest from it is nearest the tip.
        // Otherwise (the rim also cuts the head, or nothing leaves) the book's rule:
        // the smallest M (undistorted) is nearest the tip.
        int shaft = -1, leaving = 0;
        for (std::size_t k = 0; k < nparts; ++k)
            if (root(static_cast<int>(k)) == r && w.parts[k].leaves)
                ++leaving, shaft = static_cast<int>(k);
        const Strip* best = nullptr;
        int count = 0;
        double key = 0;
        for (const Strip& s : w.strips) {
            if (root(s.part_a) != r) continue;
            ++count;
            const double k =
                leaving == 1 ? -std::hypot(s.e.x - w.centroids.at<double>(w.parts[shaft].label, 0),
                                           s.e.y - w.centroids.at<double>(w.parts[shaft].label, 1))
                             : undistorted_diameter(s.e, s.a, s.b, s.diameter_px);
            if (!best || k < key) best = &s, key = k;
        }
        StripMarker& m = out[found];
        m = {};
        m.a = best->a, m.b = best->b, m.c = best->c, m.d = best->d, m.e = best->e;
        m.diameter_px = best->diameter_px;
        // The strip nearest the tip has the head on one side and a band it shares with
        // the next strip on the other: the band is a clean stretch of shaft (the head
        // may be rounded, shadowed or cut), so its side gives M when it is known.
        int uses_a = 0, uses_b = 0;
        for (const Strip& s : w.strips)
            for (int part : {s.part_a, s.part_b})
                uses_a += part == best->part_a, uses_b += part == best->part_b;
        if ((uses_a > 1) != (uses_b > 1)) {
            const bool band_a = uses_a > 1;
            const double used_mid = best->width_a >= best->width_b ? best->mid_a : best->mid_b;
            const double shift = (band_a ? best->mid_a : best->mid_b) - used_mid;
            m.diameter_px = band_a ? best->width_a : best->width_b;
            m.e = {m.e.x + shift * best->v.x, m.e.y + shift * best->v.y};
        }
        m.strips = count;
        locate(m);
        roots[found++] = r;
    }
    // Most strips first: the likeliest marker.
    std::sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(found),
              [](const StripMarker& a, const StripMarker& b) { return a.strips > b.strips; });
    return found;
}

}  // namespace endotower::vision
