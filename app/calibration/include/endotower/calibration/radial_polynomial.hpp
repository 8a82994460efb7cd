// The book's radial distortion model (eq. 2.6-2.15, appendix I). About the image
// centre c, a point at corrected radius r is seen at distorted radius
//   r' = r - dr(r),  dr(r) = k0 r + k1 r^3 + ... + kM r^(2M+1)   (odd polynomial)
// so the polynomial maps the corrected plane to the distorted one: exactly the
// inverse mapping a remap table needs (one lookup per corrected pixel).
#pragma once

#include <string>
#include <vector>

namespace endotower::calibration {

struct RadialSample {
    double r = 0;   // actual (corrected) radius, px
    double dr = 0;  // distortion at r: actual - measured radius, px
};

struct RadialPolynomial {
    std::vector<double> k;  // k[j] multiplies r^(2j+1); order = 2 k.size() - 1
    double cx = 0, cy = 0;  // the centre the radii are measured from

    int order() const { return 2 * static_cast<int>(k.size()) - 1; }
    double distortion(double r) const;  // dr(r)
    double distorted_radius(double r) const { return r - distortion(r); }
    // Corrected radius seen at distorted radius rd (Newton); false past the fold.
    bool corrected_radius(double rd, double& r) const;
    // True if r - dr(r) strictly grows on [0, r_max] (an invertible lens model).
    bool monotonic(double r_max) const;
};

struct RadialFit {
    RadialPolynomial poly;
    double total_error = 0;  // 1/2 sum of squared residuals: the book's "least squares
                             // total error" (table 2.4; appendix I's mean error)
    double max_abs_error = 0;
};

// Least squares K = (A^T A)^-1 A^T Y (eq. 2.15), solved by QR on scaled columns so
// orders up to 9 stay well conditioned. `order` is odd, 1..9. False with `error`
// when there are fewer samples than coefficients, the radii cannot separate them
// (rank deficient), or the fitted model folds over (not monotonic) within `r_max`
// (0 = the largest sample radius).
bool fit_radial_polynomial(const std::vector<RadialSample>& samples, int order, RadialFit& out,
                           std::string& error, double r_max = 0);

}  // namespace endotower::calibration
