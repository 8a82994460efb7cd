#include "world.hpp"

#include <algorithm>
#include <cmath>

#include "rng.hpp"

namespace endotower::scene::detail {

void Box::add(const Box& b) {
    if (b.x0 > b.x1) return;
    if (x0 > x1) {
        *this = b;
        return;
    }
    x0 = std::min(x0, b.x0);
    y0 = std::min(y0, b.y0);
    x1 = std::max(x1, b.x1);
    y1 = std::max(y1, b.y1);
}

namespace {

constexpr double kNear = 2.0;  // mm; nothing closer to the lens is drawn

// Conservative box of a segment of radius r in the undistorted image.
Box segment_box(const CameraModel& cam, Vec3 a, Vec3 b, double r) {
    if (a.z < kNear && b.z < kNear) return {};
    if (a.z < kNear) a = a + ((kNear - a.z) / (b.z - a.z)) * (b - a);
    if (b.z < kNear) b = b + ((kNear - b.z) / (a.z - b.z)) * (a - b);
    double xa, ya, xb, yb;
    cam.project_undistorted(a, xa, ya);
    cam.project_undistorted(b, xb, yb);
    const double zmin = std::min(a.z, b.z) - r;
    const double m = zmin > kNear ? r * std::max(cam.fx, cam.fy) / zmin + 3 : 1e7;
    return {static_cast<float>(std::min(xa, xb) - m), static_cast<float>(std::min(ya, yb) - m),
            static_cast<float>(std::max(xa, xb) + m), static_cast<float>(std::max(ya, yb) + m)};
}

// Ray (origin 0, unit d) against a capsule; t or -1 (iq's closed form).
double capsule_t(Vec3 d, Vec3 pa, Vec3 pb, double r) {
    const Vec3 ba = pb - pa, oa = -pa;
    const double baba = dot(ba, ba), bard = dot(ba, d), baoa = dot(ba, oa), rdoa = dot(d, oa),
                 oaoa = dot(oa, oa);
    const double a = baba - bard * bard, b = baba * rdoa - baoa * bard,
                 c = baba * oaoa - baoa * baoa - r * r * baba;
    double h = b * b - a * c;
    if (h >= 0 && a > 1e-12) {
        const double t = (-b - std::sqrt(h)) / a, y = baoa + t * bard;
        if (y > 0 && y < baba) return t;
        const Vec3 oc = y <= 0 ? oa : -pb;
        const double b2 = dot(d, oc), c2 = dot(oc, oc) - r * r;
        h = b2 * b2 - c2;
        if (h > 0) return -b2 - std::sqrt(h);
    }
    return -1;
}

}  // namespace

Hit FrameWorld::trace(Vec3 d, float xu, float yu, int skip_tool) const {
    Hit best;
    for (const Shaft& s : shafts) {
        if (s.tool == skip_tool || !s.box.contains(xu, yu)) continue;
        // Side: |(t d - head) x axis| = r, with 0 <= along <= len.
        const Vec3 w = -s.head;
        const Vec3 m = d - dot(d, s.axis) * s.axis, q = w - dot(w, s.axis) * s.axis;
        const double A = dot(m, m), B = dot(m, q), C = dot(q, q) - s.r * s.r;
        const double disc = B * B - A * C;
        if (A > 1e-12 && disc >= 0) {
            const double t = (-B - std::sqrt(disc)) / A;
            const double along = t * dot(d, s.axis) + dot(w, s.axis);
            if (t > kNear && t < best.t && along >= 0 && along <= s.len) {
                best.t = t;
                best.n = normalized(t * m + q);
                best.along = along;
                best.id = s.id;
                best.tool = s.tool;
                best.flat = s.flat;
                best.mat = s.mat;
                best.surface = Surface::kShaft;
                for (int i = 0; i < s.nstrips; ++i)
                    if (along >= s.strips[i][0] && along < s.strips[i][1])
                        best.surface = Surface::kStrip, best.id = s.id + 1;
                if (best.surface == Surface::kShaft && along < s.collar)
                    best.surface = Surface::kMetal, best.id = s.id + 2;
            }
        }
        // The shaft's end face at the head.
        const double da = dot(d, s.axis);
        if (std::abs(da) > 1e-9) {
            const double t = dot(s.head, s.axis) / da;
            if (t > kNear && t < best.t && norm(t * d - s.head) <= s.r) {
                best.t = t;
                best.n = da > 0 ? -s.axis : s.axis;
                best.along = 0;
                best.id = s.id + 2;
                best.tool = s.tool;
                best.flat = s.flat;
                best.mat = Material::kMetal;
                best.surface = Surface::kMetal;
            }
        }
    }
    for (const Capsule& c : caps) {
        if (c.tool == skip_tool || !c.box.contains(xu, yu)) continue;
        const double t = capsule_t(d, c.a, c.b, c.r);
        if (t > kNear && t < best.t) {
            const Vec3 p = t * d, ba = c.b - c.a;
            const double h = std::clamp(dot(p - c.a, ba) / dot(ba, ba), 0.0, 1.0);
            best.t = t;
            best.n = normalized(p - (c.a + h * ba));
            best.along = h * norm(ba);
            best.id = c.id;
            best.tool = c.tool;
            best.flat = c.flat;
            best.mat = c.mat;
            best.surface = c.jaw ? Surface::kJaw
                                 : (c.mat == Material::kMetal ? Surface::kMetal : Surface::kShaft);
            best.serrated = c.serrated;
        }
    }
    for (const Flap& f : flaps) {
        if (!f.box.contains(xu, yu) || d.z <= 1e-9) continue;
        const double t = f.c.z / d.z;
        if (t <= kNear || t >= best.t) continue;
        const Vec3 p = t * d;
        const double ex = (p.x - f.c.x) / f.rx, ey = (p.y - f.c.y) / f.ry;
        // A ragged rim, so the flap does not read as a perfect ellipse.
        const double ang = std::atan2(ey, ex);
        const double rim = 1 + 0.1 * std::sin(3 * ang + f.id) + 0.05 * std::sin(7 * ang + 2 * f.id);
        if (ex * ex + ey * ey > rim * rim) continue;
        best.t = t;
        best.n = normalized(Vec3{ex * 0.9, ey * 0.9, -1});
        best.along = 0;
        best.id = f.id;
        best.tool = -1;
        best.flat = nullptr;
        best.surface = Surface::kFlap;
    }
    return best;
}

bool SceneModel::init(const Scenario& s, std::uint64_t seed_in, std::string& error) {
    sc = s;
    seed = seed_in;
    cam = make_camera(s.camera, s.width, s.height);
    // The tissue plane: through (0, 0, distance), normal tilted from -z.
    plane_n = rotation({1, 0, 0}, s.tissue.tilt_deg[0]) *
              (rotation({0, 1, 0}, s.tissue.tilt_deg[1]) * Vec3{0, 0, -1});
    plane_o = {0, 0, s.tissue.distance_mm};
    plane_e1 = normalized(Vec3{1, 0, 0} - plane_n.x * plane_n);
    plane_e2 = cross(plane_e1, plane_n);
    const double duration = s.frames / s.fps + 1.0;
    tools.resize(s.tools.size());
    flat_colors.assign(s.tools.size(), {0, 0, 0});
    for (std::size_t i = 0; i < s.tools.size(); ++i) {
        tools[i].compile(s.tools[i], s.fps, duration, seed);
        if (s.tools[i].color) {
            for (int k = 0; k < 3; ++k) {
                // Radiance that the tone curve (1 - e^-x, sRGB) maps back to the colour.
                const double c = (*s.tools[i].color)[k] / 255.0;
                const double lin = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
                flat_colors[i][k] = static_cast<float>(-std::log(1 - std::min(lin, 0.999)));
            }
        }
    }
    endoscope.compile(s.endoscope, s.fps, plane_n, plane_o);
    if (s.target.kind != TargetKind::kNone) return true;

    // Texture patch: what the first frame sees of the plane, plus a margin; texels
    // slightly finer than a pixel there.
    double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
    for (int i = 0; i <= 64; ++i) {
        const double a = 2 * M_PI * i / 64, rr = i == 64 ? 0 : cam.fov_radius;
        double xu, yu;
        if (!cam.undistort(cam.fov_cx + rr * std::cos(a), cam.fov_cy + rr * std::sin(a), xu, yu))
            continue;
        const Vec3 d = normalized(cam.ray(xu, yu));
        const double dn = dot(plane_n, d);
        if (dn > -0.05) continue;
        const Vec3 p = (dot(plane_n, plane_o) / dn) * d;
        const double u = dot(p - plane_o, plane_e1), v = dot(p - plane_o, plane_e2);
        u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
    if (u0 > u1) u0 = v0 = -50, u1 = v1 = 50;
    const double mu = 0.15 * (u1 - u0), mv = 0.15 * (v1 - v0);
    u0 -= mu, u1 += mu, v0 -= mv, v1 += mv;
    double texel = 0.9 * s.tissue.distance_mm / cam.fx;
    texel = std::max(texel, std::max(u1 - u0, v1 - v0) / 2500.0);
    const int tw = static_cast<int>(std::ceil((u1 - u0) / texel)),
              th = static_cast<int>(std::ceil((v1 - v0) / texel));
    if (!tex.generate(s.tissue, u0, v0, texel, tw, th, stream_seed(seed, kTagTexture), error))
        return false;
    const bool changes = std::any_of(s.endoscope.begin(), s.endoscope.end(),
                                     [](const CameraSegment& c) { return c.background; });
    if (changes) {
        TissueSpec other = s.tissue;
        other.image.clear();
        other.fat = std::min(1.0, other.fat + 0.3);
        if (!tex2.generate(other, u0, v0, texel, tw, th, stream_seed(seed, kTagTexture2), error))
            return false;
    }
    return true;
}

double SceneModel::light_at(int frame) const {
    const double f = sc.frames > 1 ? static_cast<double>(frame) / (sc.frames - 1) : 0.0;
    return sc.light_from + f * (sc.light_to - sc.light_from);
}

double SceneModel::target_distance(int frame) const {
    const TargetSpec& t = sc.target;
    double end = 0;
    for (std::size_t i = 0; i < t.distances_mm.size(); ++i) {
        end +=
            t.frames_per_distance.size() == 1 ? t.frames_per_distance[0] : t.frames_per_distance[i];
        if (frame < end - 1e-9) return t.distances_mm[i];
    }
    return t.distances_mm.back();
}

bool SceneModel::inside_regions(double u, double v) const {
    for (const RegionSpec& r : sc.regions) {
        bool in = false;
        const auto& p = r.polygon_mm;
        for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
            if ((p[i][1] > v) != (p[j][1] > v) &&
                u < (p[j][0] - p[i][0]) * (v - p[i][1]) / (p[j][1] - p[i][1]) + p[i][0])
                in = !in;
        if (in) return true;
    }
    return false;
}

double SceneModel::deform_at(double t) const {
    const DeformationSpec& d = sc.deformation;
    if (!d.on()) return 0;
    const double x = std::clamp((t * sc.fps - d.from_frame) / std::max(1e-9, d.frames), 0.0, 1.0);
    return x * x * (3 - 2 * x);
}

void SceneModel::displace(double u, double v, double s, double& du, double& dv) const {
    const DeformationSpec& d = sc.deformation;
    const double r2 = (u - d.center_mm[0]) * (u - d.center_mm[0]) + (v - d.center_mm[1]) * (v - d.center_mm[1]);
    const double g = s * std::exp(-r2 / (2 * d.radius_mm * d.radius_mm));
    du = g * d.push_mm[0];
    dv = g * d.push_mm[1];
}

void SceneModel::undeform(double& u, double& v, double s) const {
    // Fixed point x = q - D(x): converges while |grad D| < 1, i.e. push < 1.6 radius
    // (the parser's limit); 6 steps reach 1e-4 mm for the suites' pushes.
    const double qu = u, qv = v;
    for (int i = 0; i < 6; ++i) {
        double du, dv;
        displace(u, v, s, du, dv);
        u = qu - du;
        v = qv - dv;
    }
}

FrameWorld SceneModel::world_at(double t, int frame) const {
    FrameWorld w;
    w.deform = deform_at(t);
    w.cam = endoscope.at(t);
    w.light = light_at(frame);
    w.background = endoscope.background_at(t);
    if (sc.target.kind != TargetKind::kNone) {
        w.target = true;
        w.target_z = target_distance(frame);
        w.pn = {0, 0, -1};
        w.po = {sc.target.offset_mm[0], sc.target.offset_mm[1], w.target_z};
        w.pe1 = {1, 0, 0};
        w.pe2 = {0, 1, 0};
    } else {
        const Mat3 rt = w.cam.r_wc.transposed();
        w.pn = rt * plane_n;
        w.po = w.cam.to_camera(plane_o);
        w.pe1 = rt * plane_e1;
        w.pe2 = rt * plane_e2;
    }
    w.ph = dot(w.pn, w.po);
    // Auto exposure on the background's distance along the optical axis (a camera
    // head's AGC): a near background does not saturate; a far one stays dim.
    const double axis_t = w.pn.z < -1e-9 ? w.ph / w.pn.z : 1e9;
    w.exposure = std::clamp((axis_t / 110.0) * (axis_t / 110.0), 0.15, 1.0);
    const Mat3 rt = w.cam.r_wc.transposed();
    for (std::size_t i = 0; i < tools.size(); ++i) {
        const ToolSpec& spec = sc.tools[i];
        const ToolPose pw = tools[i].at(t);
        ToolState ts;
        ts.pose = pw;
        ts.pose.head = w.cam.to_camera(pw.head);
        ts.pose.tip = w.cam.to_camera(pw.tip);
        ts.pose.axis = rt * pw.axis;
        ts.pivot = w.cam.to_camera(spec.pivot);
        const Vec3 a = ts.pose.axis, h = ts.pose.head, f = -a;
        // Roll 0: the jaws open across the view (in the plane of the axis and the
        // image's sideways direction), so an open tool shows both jaws.
        Vec3 r0 = Vec3{0, 0, 1} - a.z * a;
        if (norm(r0) < 1e-6) r0 = Vec3{0, 1, 0} - a.y * a;
        const Vec3 e0 = normalized(cross(a, normalized(r0)));
        const double roll = pw.roll_deg * M_PI / 180;
        ts.open_dir = std::cos(roll) * e0 + std::sin(roll) * cross(a, e0);
        const JawGeometry g = jaw_geometry(spec.tip, spec.diameter_mm);
        const float* flat = spec.color ? flat_colors[i].data() : nullptr;
        const int base = 10 + 8 * static_cast<int>(i);

        Shaft sh;
        sh.head = h;
        sh.axis = a;
        sh.r = spec.diameter_mm / 2;
        sh.len = norm(ts.pivot - h) + 150;
        sh.mat = spec.shaft;
        sh.collar = spec.shaft == Material::kDark ? 0.8 * spec.diameter_mm : 0;
        sh.nstrips = std::min(spec.markers.count, 8);
        for (int k = 0; k < sh.nstrips; ++k) {
            sh.strips[k][0] =
                spec.markers.offset_mm + k * (spec.markers.width_mm + spec.markers.gap_mm);
            sh.strips[k][1] = sh.strips[k][0] + spec.markers.width_mm;
        }
        sh.id = base;
        sh.tool = static_cast<int>(i);
        sh.flat = flat;
        sh.box = segment_box(cam, h, h + sh.len * a, sh.r);
        w.shafts.push_back(sh);

        const bool open = pw.jaw == Jaw::kOpen;
        const double half = g.half_angle_deg * M_PI / 180;
        for (int k = 0; k < (open ? 2 : 1); ++k) {
            Capsule c;
            const Vec3 dir =
                open ? std::cos(half) * f + ((k == 0 ? 1.0 : -1.0) * std::sin(half)) * ts.open_dir
                     : f;
            c.a = h;
            c.b = h + g.length * dir;
            c.r = open ? g.r_open : g.r_closed;
            c.jaw = true;
            c.serrated = spec.tip == TipType::kGrasper;
            c.id = base + 3 + k;
            c.tool = static_cast<int>(i);
            c.flat = flat;
            c.box = segment_box(cam, c.a, c.b, c.r);
            ts.jaw_end[k] = c.b + c.r * dir;
            w.caps.push_back(c);
        }
        if (!open) ts.jaw_end[1] = ts.jaw_end[0];
        w.tools.push_back(ts);
    }
    const double f = sc.frames > 1 ? std::clamp(t * sc.fps / (sc.frames - 1), 0.0, 1.0) : 0.0;
    for (std::size_t i = 0; i < sc.distractors.size(); ++i) {
        const DistractorSpec& d = sc.distractors[i];
        Capsule c;
        c.a = w.cam.to_camera(lerp(d.from[0], d.to[0], f));
        c.b = w.cam.to_camera(lerp(d.from[1], d.to[1], f));
        c.r = d.diameter_mm / 2;
        c.mat = d.material;
        c.id = 100 + static_cast<int>(i);
        c.box = segment_box(cam, c.a, c.b, c.r);
        w.caps.push_back(c);
    }
    for (std::size_t i = 0; i < sc.occluders.size(); ++i) {
        const OccluderSpec& o = sc.occluders[i];
        Flap fl;
        fl.c = w.cam.to_camera(lerp(o.from, o.to, f));
        fl.rx = o.radius_mm[0];
        fl.ry = o.radius_mm[1];
        fl.id = 200 + static_cast<int>(i);
        const double r = std::max(fl.rx, fl.ry) * 1.2;
        fl.box = segment_box(cam, fl.c, fl.c, r);
        w.flaps.push_back(fl);
    }
    return w;
}

}  // namespace endotower::scene::detail
