#include "endotower/vision/line2.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::vision {

double Segment::length() const { return std::hypot(b.x - a.x, b.y - a.y); }

double distance_to_line(Point2 p, const Segment& s) {
    // a x + b y + c = 0 through s.a and s.b.
    const double a = s.b.y - s.a.y, b = s.a.x - s.b.x;
    const double c = -(a * s.a.x + b * s.a.y);
    const double n = std::hypot(a, b);
    if (n == 0) return std::hypot(p.x - s.a.x, p.y - s.a.y);
    return std::abs(a * p.x + b * p.y + c) / n;
}

double max_end_distance(const Segment& s, const Segment& to) {
    return std::max(distance_to_line(s.a, to), distance_to_line(s.b, to));
}

double angle_between_deg(const Segment& s, const Segment& t) {
    const double a1 = std::atan2(s.b.y - s.a.y, s.b.x - s.a.x);
    const double a2 = std::atan2(t.b.y - t.a.y, t.b.x - t.a.x);
    double d = std::fmod(std::abs(a1 - a2), M_PI);
    if (d > M_PI / 2) d = M_PI - d;
    return d * 180.0 / M_PI;
}

SlopeLine SlopeLine::through(const Segment& s) {
    return through(s, std::abs(s.b.x - s.a.x) >= std::abs(s.b.y - s.a.y));
}

SlopeLine SlopeLine::through(const Segment& s, bool x_major) {
    SlopeLine l;
    l.x_major = x_major;
    const double du = x_major ? s.b.x - s.a.x : s.b.y - s.a.y;
    const double dv = x_major ? s.b.y - s.a.y : s.b.x - s.a.x;
    l.m = du != 0 ? dv / du : 0.0;
    l.b = (x_major ? s.a.y : s.a.x) - l.m * (x_major ? s.a.x : s.a.y);
    return l;
}

SlopeLine SlopeLine::swapped() const {
    // v = m u + b  <=>  u = v / m - b / m
    SlopeLine l;
    l.x_major = !x_major;
    l.m = m != 0 ? 1.0 / m : 1e9;
    l.b = m != 0 ? -b / m : 0.0;
    return l;
}

Point2 SlopeLine::at(double t) const {
    const double v = m * t + b;
    return x_major ? Point2{t, v} : Point2{v, t};
}

double SlopeLine::distance(Point2 p) const {
    const double u = x_major ? p.x : p.y, v = x_major ? p.y : p.x;
    return std::abs(m * u - v + b) / std::sqrt(m * m + 1.0);
}

}  // namespace endotower::vision
