#include "endotower/sci/sci_functions.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::sci {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

Vec3d add(Vec3d a, Vec3d b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
Vec3d sub(Vec3d a, Vec3d b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Vec3d mul(Vec3d a, double s) {
    return {a.x * s, a.y * s, a.z * s};
}
double dot(Vec3d a, Vec3d b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
double norm(Vec3d a) {
    return std::sqrt(dot(a, a));
}

// Rz(g) Ry(b) Rx(a), row-major 3x3.
std::array<double, 9> rotation(const Vec3d& deg) {
    const double ca = std::cos(deg.x * kDeg), sa = std::sin(deg.x * kDeg);
    const double cb = std::cos(deg.y * kDeg), sb = std::sin(deg.y * kDeg);
    const double cg = std::cos(deg.z * kDeg), sg = std::sin(deg.z * kDeg);
    return {cg * cb,
            cg * sb * sa - sg * ca,
            cg * sb * ca + sg * sa,
            sg * cb,
            sg * sb * sa + cg * ca,
            sg * sb * ca - cg * sa,
            -sb,
            cb * sa,
            cb * ca};
}

double cross2(double ax, double ay, double bx, double by) {
    return ax * by - ay * bx;
}

}  // namespace

Vec3d orientation_angles_deg(const Vec3d& d) {
    auto angle = [](double a, double b, double c) {
        return std::atan2(a, std::hypot(b, c)) / kDeg;
    };
    return {angle(d.x, d.y, d.z), angle(d.y, d.x, d.z), angle(d.z, d.x, d.y)};
}

void ImageBox::reset() {
    position_ = {0, 0, kDepthMm};
    angles_ = {};
    grabbed_ = placed_ = false;
}

void ImageBox::grab(const Vec3d& tip_mm, const Vec3d& axis_dir) {
    grab_tip_ = tip_mm;
    grab_angles_ = orientation_angles_deg(axis_dir);
    grab_position_ = position_;
    grab_box_angles_ = angles_;
    grabbed_ = true;
    placed_ = false;
}

void ImageBox::follow(const Vec3d& tip_mm, const Vec3d& axis_dir) {
    if (!grabbed_) return;
    // Eq. 4.33: the cube moves by the tool's translation and rotation since the grab.
    position_ = add(grab_position_, sub(tip_mm, grab_tip_));
    angles_ = add(grab_box_angles_, sub(orientation_angles_deg(axis_dir), grab_angles_));
}

bool ImageBox::place(const Vec3d& target_mm, double tolerance_mm) {
    grabbed_ = false;
    if (norm(sub(position_, target_mm)) > tolerance_mm) return false;
    position_ = target_mm;
    placed_ = true;
    return true;
}

std::array<float, 16> ImageBox::camera_from_model() const {
    const std::array<double, 9> r = rotation(angles_);
    std::array<float, 16> m{};
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) m[4 * c + row] = static_cast<float>(r[3 * row + c]);
    m[12] = static_cast<float>(position_.x);
    m[13] = static_cast<float>(position_.y);
    m[14] = static_cast<float>(position_.z);
    m[15] = 1;
    return m;
}

int ImageBox::face_under(double px, double py, const hal::SceneCamera& cam) const {
    if (!cam.valid()) return -1;
    const std::array<double, 9> r = rotation(angles_);
    auto to_camera = [&](Vec3d p) {
        return Vec3d{r[0] * p.x + r[1] * p.y + r[2] * p.z + position_.x,
                     r[3] * p.x + r[4] * p.y + r[5] * p.z + position_.y,
                     r[6] * p.x + r[7] * p.y + r[8] * p.z + position_.z};
    };
    const double h = kEdgeMm / 2;
    int best = -1;
    double best_z = 1e300;
    for (int f = 0; f < 6; ++f) {
        const int axis = f / 2;
        const double s = f % 2 == 0 ? 1.0 : -1.0;
        Vec3d n;
        (axis == 0 ? n.x : axis == 1 ? n.y : n.z) = s;
        const Vec3d centre = to_camera(mul(n, h));
        const Vec3d normal = sub(to_camera(n), to_camera({}));
        if (dot(normal, centre) >= 0 || centre.z <= cam.near_mm) continue;  // faces away
        // The face's corners, in order around it.
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        std::array<std::array<double, 2>, 4> q{};
        const std::array<std::array<double, 2>, 4> uv = {{{-h, -h}, {h, -h}, {h, h}, {-h, h}}};
        bool in_front = true;
        for (int k = 0; k < 4; ++k) {
            double p[3];
            p[axis] = s * h, p[u] = uv[k][0], p[v] = uv[k][1];
            const Vec3d c = to_camera({p[0], p[1], p[2]});
            in_front = in_front && c.z > cam.near_mm;
            q[k] = {cam.fx * c.x / c.z + cam.cx, cam.fy * c.y / c.z + cam.cy};
        }
        if (!in_front) continue;
        // Inside a convex quad: the same side of all four edges.
        int pos = 0, neg = 0;
        for (int k = 0; k < 4; ++k) {
            const auto& a = q[k];
            const auto& b = q[(k + 1) % 4];
            const double c = cross2(b[0] - a[0], b[1] - a[1], px - a[0], py - a[1]);
            pos += c > 0, neg += c < 0;
        }
        if ((pos == 0 || neg == 0) && centre.z < best_z) best = f, best_z = centre.z;
    }
    return best;
}

void SutureThread::reset(const Vec3d& a, const Vec3d& b) {
    for (int i = 0; i < kNodes; ++i) {
        x_[i] = add(a, mul(sub(b, a), static_cast<double>(i) / (kNodes - 1)));
        v_[i] = {};
    }
    carry_s_ = 0;
}

void SutureThread::step(const Vec3d& a, const Vec3d& b, double dt_s) {
    carry_s_ += std::max(0.0, dt_s);
    // A long gap (a dropped tool) would take many sub-steps; a second is plenty to settle.
    carry_s_ = std::min(carry_s_, 1.0);
    while (carry_s_ >= kStepS - 1e-12) {
        substep(a, b);
        carry_s_ -= kStepS;
    }
    x_[0] = a, x_[kNodes - 1] = b;
}

void SutureThread::substep(const Vec3d& a, const Vec3d& b) {
    const double rest = params_.length_mm / (kNodes - 1);
    x_[0] = a, x_[kNodes - 1] = b;
    v_[0] = v_[kNodes - 1] = {};
    std::array<Vec3d, kNodes> force{};
    for (int i = 0; i + 1 < kNodes; ++i) {
        const Vec3d d = sub(x_[i + 1], x_[i]);
        const double len = norm(d);
        if (len <= 1e-12) continue;
        // Hooke along the segment, per unit mass.
        const Vec3d f = mul(d, params_.stiffness * (len - rest) / len);
        force[i] = add(force[i], f);
        force[i + 1] = sub(force[i + 1], f);
    }
    // Explicit Euler: positions advance with the old velocities.
    for (int i = 1; i + 1 < kNodes; ++i) {
        Vec3d acc = sub(force[i], mul(v_[i], params_.damping));
        acc.y += params_.gravity_mm_s2;
        x_[i] = add(x_[i], mul(v_[i], kStepS));
        v_[i] = add(v_[i], mul(acc, kStepS));
    }
}

}  // namespace endotower::sci
