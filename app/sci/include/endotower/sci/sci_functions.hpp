// The SCI's 3-D functions (book ch. 4, table 4.3), in the endoscope's camera frame
// (mm; x right, y down, z forward).
//
// ImageBox: a cube of edge 40 mm drawn at 80 mm depth with zero rotation (fig. 4.36).
// grab() records the tool tip T_o and orientation R_o; follow() moves the cube by the
// deltas since then (eq. 4.33): position = p_o + (T_n - T_o), angles = a_o + (R_n - R_o),
// R = (alpha, beta, gamma) the angles of the tool's axis with the YZ, XZ and XY planes
// (eq. 4.34). The cube's rotation is Rz(gamma) Ry(beta) Rx(alpha). place() drops it on
// a target marker when its centre is within `tolerance_mm` (fig. 4.42d: snapped on);
// a placed box then stays on its target: stay_on() moves it with a target anchored to
// tissue (a tracked region, issue 7) until it is grabbed again.
// face_under() is the visible face whose projection holds a pixel (the nearest one).
//
// SutureThread: a thread of kNodes point masses joined by springs, its two ends pinned
// to the tool tips (fig. 4.37), integrated with explicit Euler in fixed 0.25 ms sub-steps.
// Explicit Euler amplifies an undamped oscillation every step; it is stable when the
// damping exceeds omega_max^2 dt = 4 k dt for the chain's fastest mode (20 per s with
// the defaults; 40 per s is used). Fixed-size arrays, no allocation.
#pragma once

#include <array>

#include "endotower/hal/overlay_scene.hpp"

namespace endotower::sci {

struct Vec3d {
    double x = 0, y = 0, z = 0;
};

Vec3d orientation_angles_deg(const Vec3d& dir);  // eq. 4.34, degrees

class ImageBox {
public:
    static constexpr double kEdgeMm = 40, kDepthMm = 80;
    void reset();
    void grab(const Vec3d& tip_mm, const Vec3d& axis_dir);
    void follow(const Vec3d& tip_mm, const Vec3d& axis_dir);
    bool place(const Vec3d& target_mm, double tolerance_mm);  // true: snapped onto it
    void release() { grabbed_ = false; }
    void stay_on(const Vec3d& target_mm) {
        if (placed_) position_ = target_mm;
    }
    bool placed() const { return placed_; }

    bool grabbed() const { return grabbed_; }
    const Vec3d& position_mm() const { return position_; }
    const Vec3d& angles_deg() const { return angles_; }
    std::array<float, 16> camera_from_model() const;  // column-major, as hal::SceneBox
    // 0..5 in hal::SceneBox's face order, or -1.
    int face_under(double px, double py, const hal::SceneCamera& camera) const;

private:
    Vec3d position_{0, 0, kDepthMm}, angles_;
    Vec3d grab_tip_, grab_angles_, grab_position_, grab_box_angles_;
    bool grabbed_ = false, placed_ = false;
};

struct SutureParams {
    double length_mm = 60;        // rest length of the whole thread
    double stiffness = 20000;     // per unit mass, 1/s^2
    double damping = 40;          // per unit mass, 1/s
    double gravity_mm_s2 = 2000;  // along +y (down in the image); a wet thread in fluid
};

class SutureThread {
public:
    static constexpr int kNodes = 16;
    static constexpr double kStepS = 0.00025;
    explicit SutureThread(SutureParams p = {}) : params_(p) {}
    void reset(const Vec3d& a, const Vec3d& b);  // a straight thread from a to b, at rest
    // Advances by dt_s (whole sub-steps; the remainder carries over) with the
    // ends at a and b.
    void step(const Vec3d& a, const Vec3d& b, double dt_s);
    const std::array<Vec3d, kNodes>& nodes() const { return x_; }

private:
    void substep(const Vec3d& a, const Vec3d& b);
    SutureParams params_;
    std::array<Vec3d, kNodes> x_{}, v_{};
    double carry_s_ = 0;
};

}  // namespace endotower::sci
