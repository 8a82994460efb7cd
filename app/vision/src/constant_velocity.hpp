// ConstantVelocity: a one-dimensional Kalman filter with state [position, velocity]
// per frame (dt = 1), the discrete white-noise acceleration model: process noise
// Q = accel^2 [[1/4, 1/2], [1/2, 1]], measurement noise R = noise^2. The likelihood
// tracker keeps one per tip coordinate and one for the axis angle of every tool, to
// predict where each tool is before the frame is split between tools, and to tell a
// measurement that jumped (a jaw of the other tool claimed at a crossing) from motion.
// Internal to app/vision; value type, no allocation.
#pragma once

namespace endotower::vision {

class ConstantVelocity {
public:
    void reset(double position) {
        x_ = position, v_ = 0, p00_ = 0, p01_ = 0, p11_ = kInitialVelocityVar;
    }
    void predict(double accel) {
        const double q = accel * accel;
        x_ += v_;
        p00_ += 2 * p01_ + p11_ + 0.25 * q;
        p01_ += p11_ + 0.5 * q;
        p11_ += q;
    }
    // Variance of the innovation z - position() for a measurement of noise `noise`.
    double innovation_var(double noise) const { return p00_ + noise * noise; }
    void update(double z, double noise) {
        const double s = innovation_var(noise), k0 = p00_ / s, k1 = p01_ / s, r = z - x_;
        x_ += k0 * r, v_ += k1 * r;
        const double p00 = (1 - k0) * p00_, p01 = (1 - k0) * p01_, p11 = p11_ - k1 * p01_;
        p00_ = p00, p01_ = p01, p11_ = p11;
    }
    void damp_velocity(double factor) { v_ *= factor; }
    double position() const { return x_; }
    double velocity() const { return v_; }

private:
    static constexpr double kInitialVelocityVar = 100.0;  // (10 px or degrees per frame)^2
    double x_ = 0, v_ = 0, p00_ = 0, p01_ = 0, p11_ = kInitialVelocityVar;
};

}  // namespace endotower::vision
