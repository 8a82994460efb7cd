#include "motion.hpp"

#include <algorithm>
#include <cmath>

#include "rng.hpp"

namespace endotower::scene::detail {

// Segment ends are sums of frames / fps; a frame exactly on a boundary belongs to
// the segment that starts there, whatever the rounding of those sums.
constexpr double kBoundary = 1e-9;

JawGeometry jaw_geometry(TipType tip, double d) {
    // Proportions of common 5 mm instruments: a grasper's jaws are about as wide as
    // the shaft when closed; scissors blades are longer and thinner.
    if (tip == TipType::kGrasper) return {2.4 * d, 0.2 * d, 0.36 * d, 24};
    return {2.6 * d, 0.12 * d, 0.2 * d, 18};
}

double anchor_offset(const ToolSpec& t, Anchor a, Jaw jaw) {
    const JawGeometry g = jaw_geometry(t.tip, t.diameter_mm);
    switch (a) {
        case Anchor::kHead:
            return 0;
        case Anchor::kMarker:
            return t.markers.offset_mm + t.markers.width_mm / 2;
        case Anchor::kTip:
            break;
    }
    const double reach = jaw == Jaw::kClosed
                             ? g.length + g.r_closed
                             : (g.length + g.r_open) * std::cos(g.half_angle_deg * M_PI / 180);
    return -reach;
}

Vec3 direction_from_angles(double yaw_deg, double pitch_deg) {
    const double y = yaw_deg * M_PI / 180, p = pitch_deg * M_PI / 180;
    return {std::cos(p) * std::sin(y), -std::sin(p), std::cos(p) * std::cos(y)};
}

void angles_from_direction(Vec3 u, double& yaw_deg, double& pitch_deg) {
    yaw_deg = std::atan2(u.x, u.z) * 180 / M_PI;
    pitch_deg = std::atan2(-u.y, std::hypot(u.x, u.z)) * 180 / M_PI;
}

ToolPose ToolMotion::pose_from_anchor(Vec3 q, double e, Jaw jaw, double roll) const {
    ToolPose p;
    p.axis = normalized(spec_.pivot - q);
    p.head = q - e * p.axis;
    p.tip = p.head + anchor_offset(spec_, Anchor::kTip, jaw) * p.axis;
    p.jaw = jaw;
    p.roll_deg = roll;
    return p;
}

void ToolMotion::compile(const ToolSpec& spec, double fps, double duration_s, std::uint64_t seed) {
    spec_ = spec;
    segs_.clear();
    const double e0 = anchor_offset(spec, spec.start_anchor, spec.jaw);
    if (spec.start_is_pose) {
        const Vec3 tip =
            spec.pivot + spec.start_depth * direction_from_angles(spec.start_yaw, spec.start_pitch);
        start_ = pose_from_anchor(tip, anchor_offset(spec, Anchor::kTip, spec.jaw), spec.jaw,
                                  spec.roll_deg);
    } else {
        start_ = pose_from_anchor(spec.start_point, e0, spec.jaw, spec.roll_deg);
    }
    ToolPose cur = start_;
    double t = 0;
    Rng rng(stream_seed(seed, kTagWander, static_cast<std::uint64_t>(spec.id)));
    for (int pass = 0; pass == 0 || (spec.repeat && t < duration_s); ++pass) {
        const double t_pass = t;
        for (const Segment& s : spec.motion) {
            Seg g;
            g.type = s.type;
            g.jaw = s.jaw.value_or(cur.jaw);
            g.roll0 = cur.roll_deg;
            g.roll1 = s.roll_deg.value_or(cur.roll_deg);
            g.e = s.type == SegmentType::kPose    ? anchor_offset(spec, Anchor::kTip, g.jaw)
                  : s.type == SegmentType::kDwell ? 0.0
                                                  : anchor_offset(spec, s.anchor, g.jaw);
            g.a0 = cur.head + g.e * cur.axis;
            const double speed = s.speed_cm_s * 10.0;  // mm/s
            double dur = s.frames / fps;
            switch (s.type) {
                case SegmentType::kMove:
                    g.a1 = s.to;
                    if (speed > 0) dur = norm(g.a1 - g.a0) / speed;
                    break;
                case SegmentType::kPose: {
                    angles_from_direction(normalized(g.a0 - spec.pivot), g.yaw0, g.pitch0);
                    g.depth0 = norm(g.a0 - spec.pivot);
                    g.yaw1 = s.yaw_deg;
                    g.pitch1 = s.pitch_deg;
                    g.depth1 = s.depth_mm;
                    g.a1 = spec.pivot + s.depth_mm * direction_from_angles(s.yaw_deg, s.pitch_deg);
                    if (speed > 0) dur = norm(g.a1 - g.a0) / speed;
                    break;
                }
                case SegmentType::kDwell:
                    g.a1 = g.a0;
                    break;
                case SegmentType::kLoop:
                    g.radius = s.radius_mm;
                    g.turns = s.turns;
                    g.center = g.a0 - Vec3{s.radius_mm, 0, 0};
                    g.a1 = g.center + s.radius_mm * Vec3{std::cos(2 * M_PI * s.turns),
                                                         std::sin(2 * M_PI * s.turns), 0};
                    if (speed > 0) dur = 2 * M_PI * s.radius_mm * s.turns / speed;
                    break;
                case SegmentType::kWander: {
                    // Straight runs between random points of a box about the start, at
                    // constant speed: the speed class holds on every frame.
                    const double len = speed * dur;
                    g.pts = {g.a0};
                    g.cum = {0};
                    while (g.cum.back() < len) {
                        const Vec3 p = g.a0 + Vec3{rng.uniform(-1, 1) * s.box_mm,
                                                   rng.uniform(-1, 1) * s.box_mm,
                                                   rng.uniform(-1, 1) * s.box_mm * 0.5};
                        const double d = norm(p - g.pts.back());
                        if (d < 0.3 * s.box_mm) continue;
                        g.pts.push_back(p);
                        g.cum.push_back(g.cum.back() + d);
                    }
                    break;
                }
            }
            g.t0 = t;
            g.t1 = t + std::max(0.0, dur);
            t = g.t1;
            segs_.push_back(g);
            cur = at(g.t1);
        }
        if (t <= t_pass) break;  // a pass without duration would never end
    }
}

ToolPose ToolMotion::at(double t) const {
    t += kBoundary;
    if (segs_.empty() || t < segs_.front().t0) return start_;
    auto it = std::upper_bound(segs_.begin(), segs_.end(), t,
                               [](double v, const Seg& s) { return v < s.t1; });
    if (it == segs_.end()) --it;
    const Seg& g = *it;
    const double f = g.t1 > g.t0 ? std::clamp((t - g.t0) / (g.t1 - g.t0), 0.0, 1.0) : 1.0;
    const double roll = g.roll0 + f * (g.roll1 - g.roll0);
    ToolPose p;
    switch (g.type) {
        case SegmentType::kMove:
            p = pose_from_anchor(lerp(g.a0, g.a1, f), g.e, g.jaw, roll);
            break;
        case SegmentType::kPose: {
            const Vec3 u = direction_from_angles(g.yaw0 + f * (g.yaw1 - g.yaw0),
                                                 g.pitch0 + f * (g.pitch1 - g.pitch0));
            p = pose_from_anchor(spec_.pivot + (g.depth0 + f * (g.depth1 - g.depth0)) * u, g.e,
                                 g.jaw, roll);
            break;
        }
        case SegmentType::kDwell:
            p = pose_from_anchor(g.a0, g.e, g.jaw, roll);
            p.dwell = t <= g.t1;
            break;
        case SegmentType::kLoop: {
            const double a = 2 * M_PI * g.turns * f;
            p = pose_from_anchor(g.center + g.radius * Vec3{std::cos(a), std::sin(a), 0}, g.e,
                                 g.jaw, roll);
            p.loop = t <= g.t1;
            break;
        }
        case SegmentType::kWander: {
            const double len = f * g.cum.back();
            std::size_t i = 1;
            while (i + 1 < g.cum.size() && g.cum[i] < len) ++i;
            Vec3 q = g.a0;
            if (g.pts.size() > 1) {
                const double seg = g.cum[i] - g.cum[i - 1];
                q = lerp(g.pts[i - 1], g.pts[i], seg > 0 ? (len - g.cum[i - 1]) / seg : 1.0);
            }
            p = pose_from_anchor(q, g.e, g.jaw, roll);
            break;
        }
    }
    return p;
}

void CameraMotion::compile(const std::vector<CameraSegment>& segs, double fps, Vec3 plane_n,
                           Vec3 plane_o) {
    segs_.clear();
    moving_ = false;
    CameraPose cur;
    double t = 0;
    for (const CameraSegment& s : segs) {
        Seg g;
        g.spec = s;
        g.start = cur;
        const Vec3 z = cur.r_wc * Vec3{0, 0, 1};
        const double nz = dot(plane_n, z);
        g.d0 = std::abs(nz) > 1e-9 ? dot(plane_n, plane_o - cur.c) / nz : 100.0;
        g.t0 = t;
        g.t1 = t + s.frames / fps;
        t = g.t1;
        moving_ = moving_ || s.move != CameraMove::kHold;
        segs_.push_back(g);
        cur = at(g.t1);
    }
}

CameraPose CameraMotion::at(double t) const {
    t += kBoundary;
    if (segs_.empty()) return {};
    if (t < segs_.front().t0) return segs_.front().start;
    auto it = std::upper_bound(segs_.begin(), segs_.end(), t,
                               [](double v, const Seg& s) { return v < s.t1; });
    const bool after = it == segs_.end();
    if (after) --it;
    const Seg& g = *it;
    const double f = after ? 1.0 : std::clamp((t - g.t0) / (g.t1 - g.t0), 0.0, 1.0);
    CameraPose p = g.start;
    const Vec3 z = g.start.r_wc * Vec3{0, 0, 1};
    switch (g.spec.move) {
        case CameraMove::kTranslate:
            p.c = g.start.c + f * (g.start.r_wc * g.spec.by);
            break;
        case CameraMove::kRotate:
            p.r_wc = g.start.r_wc * rotation({0, 0, 1}, f * g.spec.deg);
            break;
        case CameraMove::kZoom:
            p.c = g.start.c + (f * (1 - 1 / g.spec.zoom) * g.d0) * z;
            break;
        case CameraMove::kOrbit: {
            const Vec3 q = g.start.c + g.d0 * z;
            p.r_wc = g.start.r_wc * rotation({0, 1, 0}, f * g.spec.orbit_deg[0]) *
                     rotation({1, 0, 0}, f * g.spec.orbit_deg[1]);
            p.c = q - g.d0 * (p.r_wc * Vec3{0, 0, 1});
            break;
        }
        case CameraMove::kHold:
            break;
    }
    return p;
}

std::string CameraMotion::change_at(double t) const {
    t += kBoundary;
    for (const Seg& g : segs_) {
        if (t < g.t0 || t >= g.t1) continue;
        if (!g.spec.change.empty()) return g.spec.change;
        if (g.spec.background) return "background";
        switch (g.spec.move) {
            case CameraMove::kTranslate:
                return "translation";
            case CameraMove::kRotate:
                return "rotation";
            case CameraMove::kZoom:
                return g.spec.zoom >= 1 ? "zoom_in" : "zoom_out";
            case CameraMove::kOrbit:
                return "planar";
            case CameraMove::kHold:
                return "none";
        }
    }
    return "none";
}

double CameraMotion::background_at(double t) const {
    t += kBoundary;
    double b = 0;
    for (const Seg& g : segs_) {
        if (!g.spec.background || t < g.t0) continue;
        b = std::max(b, g.t1 > g.t0 ? std::clamp((t - g.t0) / (g.t1 - g.t0), 0.0, 1.0) : 1.0);
    }
    return b;
}

}  // namespace endotower::scene::detail
