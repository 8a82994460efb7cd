#include "endotower/calibration/field_of_view.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "endotower/calibration/fov_monitor.hpp"

namespace endotower::calibration {

bool FovCircle::contains(double x, double y, double margin) const {
    const double r = radius - margin;
    return r > 0 && (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r;
}

double fit_circle(const double* xs, const double* ys, int n, FovCircle& out) {
    if (n < 3) return -1;
    // Centre the data first so the normal equations stay well conditioned.
    double mx = 0, my = 0;
    for (int i = 0; i < n; ++i) mx += xs[i], my += ys[i];
    mx /= n, my /= n;
    double suu = 0, svv = 0, suv = 0, suuu = 0, svvv = 0, suvv = 0, svuu = 0;
    for (int i = 0; i < n; ++i) {
        const double u = xs[i] - mx, v = ys[i] - my;
        suu += u * u, svv += v * v, suv += u * v;
        suuu += u * u * u, svvv += v * v * v, suvv += u * v * v, svuu += v * u * u;
    }
    const double det = suu * svv - suv * suv;
    if (std::abs(det) < 1e-9 * (suu + svv) * (suu + svv) || det == 0) return -1;
    const double bu = 0.5 * (suuu + suvv), bv = 0.5 * (svvv + svuu);
    const double uc = (bu * svv - bv * suv) / det, vc = (bv * suu - bu * suv) / det;
    out.cx = uc + mx;
    out.cy = vc + my;
    out.radius = std::sqrt(uc * uc + vc * vc + (suu + svv) / n);
    double ss = 0;
    for (int i = 0; i < n; ++i) {
        const double d = std::hypot(xs[i] - out.cx, ys[i] - out.cy) - out.radius;
        ss += d * d;
    }
    return std::sqrt(ss / n);
}

bool detect_fov_circle(const GrayImage& image, FovCircle& out, std::string& error) {
    const std::string where = image.name.empty() ? std::string("image") : image.name;
    if (image.empty()) {
        error = where + ": empty image";
        return false;
    }
    const cv::Mat gray(image.height, image.width, CV_8UC1,
                       const_cast<std::uint8_t*>(image.pixels.data()));
    // Surround and disc levels from the histogram: 2nd and 75th percentiles.
    std::array<long, 256> hist{};
    for (std::uint8_t p : image.pixels) ++hist[p];
    const long total = static_cast<long>(image.pixels.size());
    auto percentile = [&](double q) {
        long acc = 0;
        for (int v = 0; v < 256; ++v)
            if ((acc += hist[v]) >= q * total) return v;
        return 255;
    };
    const int dark = percentile(0.02), bright = percentile(0.75);
    if (bright - dark < 20) {
        error = where + ": no illuminated circle (no bright disc on a dark surround; levels " +
                std::to_string(dark) + ".." + std::to_string(bright) + ")";
        return false;
    }
    cv::Mat mask;
    cv::threshold(gray, mask, dark + 0.3 * (bright - dark), 255, cv::THRESH_BINARY);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    std::size_t best = 0;
    double best_area = 0;
    for (std::size_t i = 0; i < contours.size(); ++i) {
        const double a = cv::contourArea(contours[i]);
        if (a > best_area) best_area = a, best = i;
    }
    if (best_area < 0.05 * total) {
        error = where + ": no illuminated circle (largest bright region is " +
                std::to_string(static_cast<int>(100.0 * best_area / total)) + "% of the image)";
        return false;
    }
    std::vector<cv::Point> hull;
    cv::convexHull(contours[best], hull);
    const double hull_area = cv::contourArea(hull);
    // Dense outline: the hull's vertices plus the contour points that lie on the hull.
    std::vector<double> xs, ys;
    for (const cv::Point& p : contours[best]) {
        if (p.x <= 1 || p.y <= 1 || p.x >= image.width - 2 || p.y >= image.height - 2) continue;
        if (cv::pointPolygonTest(hull, cv::Point2f(p.x, p.y), true) > -1.0) {
            // The contour runs along the outermost lit pixels; the edge lies half a pixel out.
            xs.push_back(p.x);
            ys.push_back(p.y);
        }
    }
    FovCircle c;
    const double rms = fit_circle(xs.data(), ys.data(), static_cast<int>(xs.size()), c);
    if (rms < 0 || rms > 0.02 * c.radius) {
        error = where + ": the bright region's outline is not a circle";
        return false;
    }
    const double fill = hull_area / (M_PI * c.radius * c.radius);
    if (fill < 0.8) {
        error = where + ": the bright region fills only " +
                std::to_string(static_cast<int>(fill * 100)) +
                "% of its circle (not a field-of-view disc)";
        return false;
    }
    c.radius += 0.5;
    // Refine on the rim itself: edges at the local mid level between the lit disc and
    // the surround along 64 rays (a global threshold is biased where the rim is dim).
    hal::Frame view;
    view.format = {image.width, image.height, image.width, hal::PixelFormat::kGray8};
    view.data = const_cast<std::uint8_t*>(image.pixels.data());
    const FovCheck refined = FovMonitor(c).check(view);
    if (refined.status != FovStatus::kUnknown) c = refined.circle;
    out = c;
    return true;
}

}  // namespace endotower::calibration
