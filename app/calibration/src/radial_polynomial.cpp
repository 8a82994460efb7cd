#include "endotower/calibration/radial_polynomial.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace endotower::calibration {

double RadialPolynomial::distortion(double r) const {
    // Horner in r^2: r (k0 + r^2 (k1 + r^2 (...)))
    const double r2 = r * r;
    double acc = 0;
    for (auto it = k.rbegin(); it != k.rend(); ++it) acc = acc * r2 + *it;
    return acc * r;
}

bool RadialPolynomial::corrected_radius(double rd, double& r) const {
    r = rd;
    for (int it = 0; it < 50; ++it) {
        // d/dr (r - dr(r)) = 1 - sum (2j+1) k_j r^(2j)
        const double r2 = r * r;
        double deriv = 0, p = 1;
        for (std::size_t j = 0; j < k.size(); ++j, p *= r2) deriv += (2.0 * j + 1) * k[j] * p;
        const double slope = 1.0 - deriv;
        if (slope <= 1e-9) return false;
        const double step = (distorted_radius(r) - rd) / slope;
        r -= step;
        if (std::abs(step) < 1e-10 * std::max(1.0, r)) return r >= 0;
    }
    return false;
}

bool RadialPolynomial::monotonic(double r_max) const {
    if (!std::isfinite(r_max)) return false;
    double prev = distorted_radius(0);
    // One step per pixel of radius, at least 100; capped so that no radius makes it loop
    // for long (the calibration file bounds the image to 16384 px a side: 23170 px).
    const int steps = static_cast<int>(std::clamp(r_max, 100.0, 32768.0));
    for (int i = 1; i <= steps; ++i) {
        const double v = distorted_radius(r_max * i / steps);
        if (!(v > prev)) return false;
        prev = v;
    }
    return true;
}

bool fit_radial_polynomial(const std::vector<RadialSample>& samples, int order, RadialFit& out,
                           std::string& error, double r_max) {
    if (order < 1 || order > 9 || order % 2 == 0) {
        error = "polynomial order " + std::to_string(order) + " must be odd, 1..9 (eq. 2.10)";
        return false;
    }
    const int terms = (order + 1) / 2;
    const int n = static_cast<int>(samples.size());
    if (n < terms) {
        error = "too few points for an order-" + std::to_string(order) +
                " fit: " + std::to_string(n) + " (need at least " + std::to_string(terms) + ")";
        return false;
    }
    double scale = 0;
    for (const RadialSample& s : samples) scale = std::max(scale, std::abs(s.r));
    if (scale <= 0) {
        error = "degenerate fit: every point lies at the centre";
        return false;
    }
    // Columns (r/scale)^(2j+1): the same least squares, coefficients rescaled after.
    Eigen::MatrixXd a(n, terms);
    Eigen::VectorXd y(n);
    for (int i = 0; i < n; ++i) {
        const double u = samples[i].r / scale;
        double p = u;
        for (int j = 0; j < terms; ++j, p *= u * u) a(i, j) = p;
        y(i) = samples[i].dr;
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
    if (qr.rank() < terms) {
        error = "degenerate fit: " + std::to_string(n) +
                " points at too few distinct radii for order " + std::to_string(order);
        return false;
    }
    const Eigen::VectorXd ks = qr.solve(y);
    RadialFit fit;
    fit.poly.k.resize(terms);
    for (int j = 0; j < terms; ++j) fit.poly.k[j] = ks(j) / std::pow(scale, 2 * j + 1);
    for (const RadialSample& s : samples) {
        const double e = s.dr - fit.poly.distortion(s.r);
        fit.total_error += 0.5 * e * e;
        fit.max_abs_error = std::max(fit.max_abs_error, std::abs(e));
    }
    const double limit = r_max > 0 ? r_max : scale;
    if (!fit.poly.monotonic(limit)) {
        error = "the order-" + std::to_string(order) + " fit is not monotonic within radius " +
                std::to_string(static_cast<int>(limit)) +
                " px (the corrected image would fold over): use a lower order or more points";
        return false;
    }
    out = fit;
    return true;
}

}  // namespace endotower::calibration
