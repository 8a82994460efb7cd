#include "endotower/vision/gesture_features.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace endotower::vision {

namespace {

double polygon_perimeter(const std::vector<cv::Point>& p) {
    return cv::arcLength(p, true);
}

// Max and min Feret diameters of a convex polygon (counter-clockwise or clockwise):
// the diameter is the largest vertex distance; the width is the smallest, over the
// edges, of the largest vertex distance from the edge's line (rotating calipers
// by brute force: hulls here have tens of vertices).
void feret(const std::vector<cv::Point>& hull, double& max_d, double& min_d) {
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
        const cv::Point a = hull[i], b = hull[(i + 1) % n];
        const double ex = b.x - a.x, ey = b.y - a.y, len = std::hypot(ex, ey);
        if (len <= 0) continue;
        double far = 0;
        for (const cv::Point& p : hull)
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

std::array<float, GestureFeatures::kExtendedCount> GestureFeatures::as_vector() const {
    return {static_cast<float>(compactness), static_cast<float>(roughness),
            static_cast<float>(elongation),  static_cast<float>(feret_elongation),
            static_cast<float>(max_changes), static_cast<float>(min_changes),
            static_cast<float>(solidity),    static_cast<float>(hu1),
            static_cast<float>(hu2)};
}

GestureFeatures measure_gesture_features(const std::uint8_t* mask, int width, int height,
                                         int stride) {
    GestureFeatures f;
    if (mask == nullptr || width <= 0 || height <= 0) return f;
    // findContours wants a writable, zero-bordered copy.
    cv::Mat m(height + 2, width + 2, CV_8U, cv::Scalar(0));
    const cv::Mat in(height, width, CV_8U, const_cast<std::uint8_t*>(mask),
                     static_cast<std::size_t>(stride));
    cv::Mat inner = m(cv::Rect(1, 1, width, height));
    cv::compare(in, 0, inner, cv::CMP_NE);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(m, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    const std::vector<cv::Point>* best = nullptr;
    double best_area = 0;
    for (const auto& c : contours) {
        const double a = std::abs(cv::contourArea(c));
        if (c.size() >= 3 && a > best_area) best = &c, best_area = a;
    }
    if (best == nullptr || best_area <= 0) return f;
    const std::vector<cv::Point>& c = *best;
    const double area = best_area, perimeter = polygon_perimeter(c);
    std::vector<cv::Point> hull;
    cv::convexHull(c, hull);
    const double hull_perimeter = polygon_perimeter(hull),
                 hull_area = std::abs(cv::contourArea(hull));

    f.compactness = perimeter * perimeter / (4.0 * M_PI * area);
    f.roughness = hull_perimeter > 0 ? perimeter / hull_perimeter : 1.0;
    const double q = perimeter / 4.0, disc = q * q - area;
    f.elongation = disc > 0 ? (q + std::sqrt(disc)) / (q - std::sqrt(disc)) : 1.0;
    double fmax = 0, fmin = 0;
    feret(hull, fmax, fmin);
    f.feret_elongation = fmin > 0 ? fmax / fmin : 1.0;
    f.solidity = hull_area > 0 ? area / hull_area : 1.0;

    // The scan lines cross at the centroid of all the mask's pixels (open jaws cut
    // off by the window may be apart); Hu moments of the blob's polygon.
    const cv::Moments all = cv::moments(inner, true);
    f.centroid_x = all.m10 / all.m00;
    f.centroid_y = all.m01 / all.m00;
    const cv::Moments mo = cv::moments(c);
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
