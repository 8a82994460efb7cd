#include "endotower/vision/gesture_features.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <span>

namespace endotower::vision {

namespace {

// Max and min Feret diameters of a convex polygon (counter-clockwise or clockwise):
// the diameter is the largest vertex distance; the width is the smallest, over the
// edges, of the largest vertex distance from the edge's line (rotating calipers
// by brute force: hulls here have tens of vertices).
void feret(std::span<const IntPoint> hull, double& max_d, double& min_d) {
    max_d = 0;
    min_d = 0;
    const std::size_t n = hull.size();
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            max_d = std::max(
                max_d, std::hypot(double(hull[i].x - hull[j].x), double(hull[i].y - hull[j].y)));
    if (n < 3) return;
    min_d = 1e300;
    for (std::size_t i = 0; i < n; ++i) {
        const IntPoint a = hull[i], b = hull[(i + 1) % n];
        const double ex = b.x - a.x, ey = b.y - a.y, len = std::hypot(ex, ey);
        if (len <= 0) continue;
        double far = 0;
        for (const IntPoint& p : hull)
            far = std::max(far, std::abs(ex * (p.y - a.y) - ey * (p.x - a.x)) / len);
        min_d = std::min(min_d, far);
    }
}

// std::lround without the library call: half away from zero (v - trunc(v) is exact).
int round_half_away(double v) {
    const long t = static_cast<long>(v);
    const double f = v - static_cast<double>(t);
    return static_cast<int>(f >= 0.5 ? t + 1 : f <= -0.5 ? t - 1 : t);
}

// 0<->1 changes along the line through (cx, cy) at `angle`, sampled every pixel
// across the whole mask; outside the mask is 0.
int changes_along(const std::uint8_t* mask, int w, int h, int stride, double cx, double cy,
                  double angle) {
    const double dx = std::cos(angle), dy = std::sin(angle);
    const int reach = static_cast<int>(std::ceil(std::hypot(double(w), double(h)))) + 1;
    int changes = 0;
    bool prev = false;
    for (int s = -reach; s <= reach; ++s) {
        const int x = round_half_away(cx + s * dx), y = round_half_away(cy + s * dy);
        const bool on = x >= 0 && y >= 0 && x < w && y < h &&
                        mask[static_cast<std::size_t>(y) * stride + x] != 0;
        if (on != prev) ++changes;
        prev = on;
    }
    return changes;
}

}  // namespace

std::array<float, GestureFeatures::kProfileCount> GestureFeatures::as_vector() const {
    std::array<float, kProfileCount> v = {
        static_cast<float>(compactness), static_cast<float>(roughness),
        static_cast<float>(elongation),  static_cast<float>(feret_elongation),
        static_cast<float>(max_changes), static_cast<float>(min_changes),
        static_cast<float>(solidity),    static_cast<float>(hu1),
        static_cast<float>(hu2),         static_cast<float>(hole1),
        static_cast<float>(hole2)};
    for (int k = 0; k < kProfileStations; ++k) {
        v[kTopologyCount + 2 * k] = profile_width[k];
        v[kTopologyCount + 2 * k + 1] = profile_runs[k];
    }
    return v;
}

void measure_tip_profile(const std::uint8_t* mask, int width, int height, int stride, double tip_x,
                         double tip_y, double axis_x, double axis_y, double radius,
                         GestureFeatures& f) {
    const double r = std::max(1.0, radius);
    const int half = static_cast<int>(std::ceil(16 * r));  // 8 r in half-pixel steps
    for (int k = 0; k < GestureFeatures::kProfileStations; ++k) {
        const double s = (0.35 + 0.7 * k) * r;
        const double cx = tip_x + s * axis_x, cy = tip_y + s * axis_y;
        // A gap of under kMinGap samples does not end a run: cracks in a jaw's mask
        // (bright ribbed metal) are not the gap between open jaws.
        constexpr int kMinGap = 4;
        int on = 0, runs = 0, run = 0, gap = kMinGap;
        for (int i = -half; i <= half + kMinGap; ++i) {
            const double t = 0.5 * i;
            const int x = round_half_away(cx - t * axis_y), y = round_half_away(cy + t * axis_x);
            const bool set = i <= half && x >= 0 && y >= 0 && x < width && y < height &&
                             mask[static_cast<std::size_t>(y) * stride + x] != 0;
            if (set) {
                ++on, ++run, gap = 0;
            } else if (++gap == kMinGap) {
                if (run >= 2) ++runs;
                run = 0;
            }
        }
        f.profile_width[k] = static_cast<float>(0.5 * on / (2 * r));
        f.profile_runs[k] = static_cast<float>(runs);
    }
}

GestureFeatures measure_gesture_features(const std::uint8_t* mask, int width, int height,
                                         int stride) {
    ContourTracer tracer;
    tracer.reserve(width, height);
    return measure_gesture_features(mask, width, height, stride, tracer);
}

bool gesture_features_valid(const std::uint8_t* mask, int width, int height, int stride,
                            ContourTracer& tracer) {
    if (mask == nullptr || width <= 0 || height <= 0) return false;
    double area = 0;
    return !tracer.largest(mask, width, height, static_cast<std::size_t>(stride), area).empty() &&
           area > 0;
}

GestureFeatures measure_gesture_features(const std::uint8_t* mask, int width, int height,
                                         int stride, ContourTracer& tracer) {
    GestureFeatures f;
    if (mask == nullptr || width <= 0 || height <= 0) return f;
    // The largest outer border, in the coordinates of a copy with a zero border (as
    // cv::findContours traced it), and its hull.
    double area = 0;
    const std::span<const IntPoint> c =
        tracer.largest(mask, width, height, static_cast<std::size_t>(stride), area);
    if (c.empty() || area <= 0) return f;
    const double perimeter = polygon_perimeter(c);
    const std::span<const IntPoint> hull = tracer.hull(c);
    const double hull_perimeter = polygon_perimeter(hull), hull_area = polygon_area(hull);

    f.compactness = perimeter * perimeter / (4.0 * M_PI * area);
    f.roughness = hull_perimeter > 0 ? perimeter / hull_perimeter : 1.0;
    const double q = perimeter / 4.0, disc = q * q - area;
    f.elongation = disc > 0 ? (q + std::sqrt(disc)) / (q - std::sqrt(disc)) : 1.0;
    double fmax = 0, fmin = 0;
    feret(hull, fmax, fmin);
    f.feret_elongation = fmin > 0 ? fmax / fmin : 1.0;
    f.solidity = hull_area > 0 ? area / hull_area : 1.0;
    int hole1 = 0, hole2 = 0;
    tracer.holes(hole1, hole2);
    f.hole1 = hole1 / area;
    f.hole2 = hole2 / area;

    // The scan lines cross at the centroid of all the mask's pixels (open jaws cut
    // off by the window may be apart); Hu moments of the blob's polygon.
    double m00 = 0, m10 = 0, m01 = 0;  // integer sums: exact, as cv::moments(mask, true)
    for (int y = 0; y < height; ++y) {
        const std::uint8_t* r = mask + static_cast<std::size_t>(y) * stride;
        long count = 0, xs = 0;
        for (int x = 0; x < width; ++x)
            if (r[x] != 0) ++count, xs += x;
        m00 += static_cast<double>(count);
        m10 += static_cast<double>(xs);
        m01 += static_cast<double>(count) * y;
    }
    f.centroid_x = m10 / m00;
    f.centroid_y = m01 / m00;
    // A header on the points (cv::Point is two ints, as IntPoint): no copy, no allocation.
    static_assert(sizeof(IntPoint) == sizeof(cv::Point));
    const cv::Mat points(static_cast<int>(c.size()), 1, CV_32SC2, const_cast<IntPoint*>(c.data()));
    const cv::Moments mo = cv::moments(points);
    double hu[7];
    cv::HuMoments(mo, hu);
    f.hu1 = hu[0];
    f.hu2 = std::sqrt(std::max(0.0, hu[1]));  // same units as hu1

    f.max_changes = 0;
    f.min_changes = 1 << 30;
    for (int k = 0; k < GestureFeatures::kScanLines; ++k) {
        const int n = changes_along(mask, width, height, stride, f.centroid_x, f.centroid_y,
                                    k * M_PI / GestureFeatures::kScanLines);
        f.max_changes = std::max(f.max_changes, n);
        f.min_changes = std::min(f.min_changes, n);
    }
    f.valid = true;
    return f;
}

}  // namespace endotower::vision
