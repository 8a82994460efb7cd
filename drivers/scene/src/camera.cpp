#include "endotower/scene/camera.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::scene {

Mat3 rotation(Vec3 axis, double deg) {
    const Vec3 u = normalized(axis);
    const double a = deg * M_PI / 180.0, c = std::cos(a), s = std::sin(a), t = 1 - c;
    return {{t * u.x * u.x + c, t * u.x * u.y - s * u.z, t * u.x * u.z + s * u.y,
             t * u.x * u.y + s * u.z, t * u.y * u.y + c, t * u.y * u.z - s * u.x,
             t * u.x * u.z - s * u.y, t * u.y * u.z + s * u.x, t * u.z * u.z + c}};
}

bool invert(const Mat3& a, Mat3& out) {
    const double* m = a.m;
    const double c0 = m[4] * m[8] - m[5] * m[7], c1 = m[5] * m[6] - m[3] * m[8],
                 c2 = m[3] * m[7] - m[4] * m[6];
    const double det = m[0] * c0 + m[1] * c1 + m[2] * c2;
    if (std::abs(det) < 1e-300) return false;
    const double i = 1.0 / det;
    out = {{c0 * i, (m[2] * m[7] - m[1] * m[8]) * i, (m[1] * m[5] - m[2] * m[4]) * i, c1 * i,
            (m[0] * m[8] - m[2] * m[6]) * i, (m[2] * m[3] - m[0] * m[5]) * i, c2 * i,
            (m[1] * m[6] - m[0] * m[7]) * i, (m[0] * m[4] - m[1] * m[3]) * i}};
    return true;
}

namespace {

// r_d / r_u as a function of r_u^2, and d(r_d)/d(r_u).
double factor(const std::vector<double>& k, double r2) {
    double f = 1.0, p = 1.0;
    for (double ki : k) {
        p *= r2;
        f += ki * p;
    }
    return f;
}
double slope(const std::vector<double>& k, double r2) {
    double f = 1.0, p = 1.0;
    for (std::size_t i = 0; i < k.size(); ++i) {
        p *= r2;
        f += static_cast<double>(2 * i + 3) * k[i] * p;
    }
    return f;
}

}  // namespace

void CameraModel::distort(double xu, double yu, double& xd, double& yd) const {
    const double dx = xu - cx, dy = yu - cy;
    const double f = factor(k, dx * dx + dy * dy);
    xd = cx + dx * f;
    yd = cy + dy * f;
}

double CameraModel::max_undistorted_radius() const {
    // The ground truth asks this for every point it projects (thousands a frame) and the
    // search below takes up to 8 (w + h) steps: the last answer is kept per thread, for
    // the same distortion and size.
    thread_local std::vector<double> last_k;
    thread_local int last_w = -1, last_h = -1;
    thread_local double last_r = 0;
    if (width == last_w && height == last_h && k == last_k) return last_r;
    // The first zero of d(r_d)/d(r_u), searched outwards; far beyond any image if none.
    const double limit = 4.0 * (width + height);
    double r = 0;
    for (const double step = 0.5; r < limit; r += step)
        if (slope(k, (r + step) * (r + step)) <= 0) break;
    last_k = k;
    last_w = width;
    last_h = height;
    last_r = std::min(r, limit);
    return last_r;
}

bool CameraModel::undistort(double xd, double yd, double& xu, double& yu) const {
    const double dx = xd - cx, dy = yd - cy;
    const double rd = std::sqrt(dx * dx + dy * dy);
    if (rd == 0) {
        xu = xd;
        yu = yd;
        return true;
    }
    // Newton on g(r) = r f(r^2) - r_d from r = r_d; barrel distortion converges from
    // below in a handful of steps.
    double r = rd;
    for (int i = 0; i < 50; ++i) {
        const double r2 = r * r;
        const double s = slope(k, r2);
        if (s <= 0) return false;
        const double step = (r * factor(k, r2) - rd) / s;
        r -= step;
        if (std::abs(step) < 1e-12 * (1 + r)) break;
    }
    if (!(r > 0) || std::abs(r * factor(k, r * r) - rd) > 1e-9 * (1 + rd)) return false;
    if (slope(k, r * r) <= 0) return false;
    xu = cx + dx * (r / rd);
    yu = cy + dy * (r / rd);
    return true;
}

bool CameraModel::project_undistorted(Vec3 p, double& xu, double& yu) const {
    if (p.z <= 1e-9) return false;
    xu = cx + fx * p.x / p.z;
    yu = cy + fy * p.y / p.z;
    return true;
}

bool CameraModel::project(Vec3 p, double& xd, double& yd) const {
    double xu, yu;
    if (!project_undistorted(p, xu, yu)) return false;
    distort(xu, yu, xd, yd);
    return true;
}

bool CameraModel::in_fov(double xd, double yd) const {
    const double dx = xd - fov_cx, dy = yd - fov_cy;
    return dx * dx + dy * dy <= fov_radius * fov_radius && xd >= -0.5 && yd >= -0.5 &&
           xd < width - 0.5 && yd < height - 0.5;
}

CameraModel make_camera(const CameraSpec& spec, int width, int height) {
    CameraModel c;
    const double h = height;
    c.width = width;
    c.height = height;
    c.fx = spec.focal * h;
    c.fy = c.fx * spec.sy_over_sx;
    // Pixel (0,0) covers [-0.5, 0.5): the sensor centre is at ((w-1)/2, (h-1)/2).
    c.fov_cx = (width - 1) / 2.0;
    c.fov_cy = (height - 1) / 2.0;
    c.cx = c.fov_cx + spec.center_offset[0] * h;
    c.cy = c.fov_cy + spec.center_offset[1] * h;
    double scale = 1.0;
    for (double ki : spec.k) {
        scale /= h * h;
        c.k.push_back(ki * scale);
    }
    c.fov_radius = spec.fov_radius * h;
    c.vignetting = spec.vignetting;
    c.blur_sigma = spec.blur_px * h / 480.0;
    return c;
}

}  // namespace endotower::scene
