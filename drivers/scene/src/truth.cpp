#include "endotower/scene/truth.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "truth_compute.hpp"

namespace endotower::scene {

namespace detail {

namespace {

// Displayed pixel of a camera-frame point; false if behind the lens or outside the
// range where the distortion model is one-to-one.
bool display(const CameraModel& cam, Vec3 p, Px& out) {
    double xu, yu;
    if (p.z < 1.0 || !cam.project_undistorted(p, xu, yu)) return false;
    if (std::hypot(xu - cam.cx, yu - cam.cy) > cam.max_undistorted_radius()) return false;
    cam.distort(xu, yu, out.x, out.y);
    return true;
}
bool in_view(const CameraModel& cam, Vec3 p, Px* out = nullptr) {
    Px q;
    if (!display(cam, p, q)) return false;
    if (out) *out = q;
    return cam.in_fov(q.x, q.y);
}
Px undistorted(const CameraModel& cam, Vec3 p) {
    Px q;
    cam.project_undistorted(p, q.x, q.y);
    return q;
}

// Along-axis distance from the head where the line H + o + s a leaves the view,
// after first being in it (0 if never in it).
double exit_along(const CameraModel& cam, Vec3 h, Vec3 a, double len) {
    bool seen = false;
    double last_in = 0;
    for (double s = 0; s <= len; s += 1.0) {
        if (in_view(cam, h + s * a)) {
            seen = true;
            last_in = s;
        } else if (seen) {
            double lo = last_in, hi = s;
            for (int i = 0; i < 40; ++i) {
                const double mid = (lo + hi) / 2;
                (in_view(cam, h + mid * a) ? lo : hi) = mid;
            }
            return lo;
        }
    }
    return last_in;
}

bool point_visible(const FrameWorld& w, const CameraModel& cam, Vec3 p, double margin, int tool) {
    if (!in_view(cam, p)) return false;
    const double dist = norm(p);
    const Vec3 d = (1.0 / dist) * p;
    const Hit h = w.trace(d, static_cast<float>(cam.cx + cam.fx * d.x / d.z),
                          static_cast<float>(cam.cy + cam.fy * d.y / d.z), tool);
    return h.t >= dist - margin && w.plane_t(d) >= dist - margin;
}

bool segments_cross(Px a, Px b, Px c, Px d) {
    auto orient = [](Px p, Px q, Px r) {
        return (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
    };
    const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a),
                 o4 = orient(c, d, b);
    return o1 * o2 < 0 && o3 * o4 < 0;
}

std::array<double, 9> plane_homography(const CameraModel& cam, const FrameWorld& w) {
    const Vec3 cols[3] = {w.pe1, w.pe2, w.po};
    std::array<double, 9> h{};
    for (int c = 0; c < 3; ++c) {
        h[c] = cam.fx * cols[c].x + cam.cx * cols[c].z;
        h[3 + c] = cam.fy * cols[c].y + cam.cy * cols[c].z;
        h[6 + c] = cols[c].z;
    }
    return h;
}

}  // namespace

void compute_truth(const SceneModel& model, const FrameWorld& w, int frame, FrameTruth& out) {
    const CameraModel& cam = model.cam;
    const Scenario& sc = model.sc;
    const double t = model.time_of(frame);
    out = FrameTruth{};
    out.frame = frame;
    out.t_ns = std::llround(frame * 1e9 / sc.fps);
    out.light = w.light;
    const double t_other = frame > 0 ? t - 1 / sc.fps : t + 1 / sc.fps;
    for (std::size_t i = 0; i < w.tools.size(); ++i) {
        const ToolSpec& spec = sc.tools[i];
        const ToolState& ts = w.tools[i];
        const Vec3 h = ts.pose.head, a = ts.pose.axis;
        const double r = spec.diameter_mm / 2;
        ToolTruth tt;
        tt.id = spec.id;
        tt.tip_mm = ts.pose.tip;
        tt.head_mm = h;
        tt.axis_dir = a;
        tt.pivot_mm = ts.pivot;
        tt.tip_px_u = undistorted(cam, ts.pose.tip);
        tt.head_px_u = undistorted(cam, h);
        display(cam, ts.pose.tip, tt.tip_px);
        display(cam, h, tt.head_px);
        angles_from_direction(normalized(ts.pose.tip - ts.pivot), tt.yaw_deg, tt.pitch_deg);
        tt.roll_deg = ts.pose.roll_deg;
        Px ahead;
        display(cam, h + 1.0 * a, ahead);
        tt.axis_deg = std::atan2(ahead.y - tt.head_px.y, ahead.x - tt.head_px.x) * 180 / M_PI;
        tt.diameter_mm = spec.diameter_mm;
        tt.tip_type = spec.tip == TipType::kGrasper ? "grasper" : "scissors";
        tt.jaw = ts.pose.jaw == Jaw::kOpen ? "open" : "closed";
        tt.gesture = tt.jaw + "_" + tt.tip_type;

        // Silhouette generators: the two lines of the cylinder tangent to the lens's view.
        const Vec3 pv = -h + dot(h, a) * a;
        const double dist = norm(pv);
        Vec3 off[2] = {{0, 0, 0}, {0, 0, 0}};
        if (dist > r) {
            const Vec3 ph = (1.0 / dist) * pv, qh = cross(a, ph);
            const double c = r / dist, s = std::sqrt(1 - c * c);
            off[0] = r * (c * ph + s * qh);
            off[1] = r * (c * ph - s * qh);
        }
        const double len = norm(ts.pivot - h) + 150;
        Px ends[2][2];
        for (int k = 0; k < 2; ++k) {
            const double s_exit = exit_along(cam, h + off[k], a, len);
            display(cam, h + off[k], ends[k][0]);
            display(cam, h + off[k] + s_exit * a, ends[k][1]);
            tt.edges_px[k] = {ends[k][0].x, ends[k][0].y, ends[k][1].x, ends[k][1].y};
        }
        tt.midline_px = {(ends[0][0].x + ends[1][0].x) / 2, (ends[0][0].y + ends[1][0].y) / 2,
                         (ends[0][1].x + ends[1][1].x) / 2, (ends[0][1].y + ends[1][1].y) / 2};
        double width = 0;
        for (int k = 0; k < 2; ++k) {
            Px step;
            display(cam, h + off[k] + 1.0 * a, step);
            const double dx = step.x - ends[k][0].x, dy = step.y - ends[k][0].y,
                         n = std::hypot(dx, dy);
            const Px o = ends[1 - k][0];
            if (n > 0)
                width += std::abs((o.x - ends[k][0].x) * dy - (o.y - ends[k][0].y) * dx) / n / 2;
        }
        tt.width_px = width;

        // Visible fraction: the axis from the tip back to 60 mm behind the head.
        const double span = norm(h - ts.pose.tip) + 60;
        int vis = 0;
        constexpr int kSamples = 48;
        for (int k = 0; k < kSamples; ++k) {
            const Vec3 p = ts.pose.tip + (span * k / (kSamples - 1)) * a;
            vis += point_visible(w, cam, p, r, static_cast<int>(i)) ? 1 : 0;
        }
        tt.visible_fraction = static_cast<double>(vis) / kSamples;
        tt.visible = vis > 0;

        for (int k = 0; k < std::min(spec.markers.count, 8); ++k) {
            const double s0 =
                spec.markers.offset_mm + k * (spec.markers.width_mm + spec.markers.gap_mm);
            const double s1 = s0 + spec.markers.width_mm;
            MarkerTruth m;
            m.strip = k;
            m.center_mm = h + ((s0 + s1) / 2) * a;
            display(cam, m.center_mm, m.center_px);
            display(cam, h + off[0] + s0 * a, m.corners_px[0]);
            display(cam, h + off[1] + s0 * a, m.corners_px[1]);
            display(cam, h + off[1] + s1 * a, m.corners_px[2]);
            display(cam, h + off[0] + s1 * a, m.corners_px[3]);
            m.visible = point_visible(w, cam, m.center_mm, r, static_cast<int>(i));
            tt.markers.push_back(m);
        }
        out.tools.push_back(tt);
        if (ts.pose.dwell &&
            std::find(out.events.begin(), out.events.end(), "dwell") == out.events.end())
            out.events.push_back("dwell");
        if (ts.pose.loop &&
            std::find(out.events.begin(), out.events.end(), "loop") == out.events.end())
            out.events.push_back("loop");
        const double speed =
            norm(model.tools[i].at(t).tip - model.tools[i].at(t_other).tip) * sc.fps / 10.0;
        out.speed_cm_s = std::max(out.speed_cm_s, speed);
    }

    // Two-tool gesture: the jaws (or the shaft next to them) of one tool cross the other's.
    if (w.tools.size() >= 2 && out.tools[0].visible && out.tools[1].visible) {
        std::vector<std::pair<Px, Px>> seg[2];
        int open = 0;
        for (int i = 0; i < 2; ++i) {
            const ToolState& ts = w.tools[i];
            const double reach = jaw_geometry(sc.tools[i].tip, sc.tools[i].diameter_mm).length;
            Px hp, e0, e1, back;
            display(cam, ts.pose.head, hp);
            display(cam, ts.jaw_end[0], e0);
            display(cam, ts.jaw_end[1], e1);
            display(cam, ts.pose.head + reach * ts.pose.axis, back);
            seg[i] = {{hp, e0}, {hp, e1}, {hp, back}};
            open += ts.pose.jaw == Jaw::kOpen ? 1 : 0;
        }
        bool cross = false;
        for (const auto& s0 : seg[0])
            for (const auto& s1 : seg[1])
                cross = cross || segments_cross(s0.first, s0.second, s1.first, s1.second);
        if (cross) out.gesture = open == 0 ? "cross" : open == 1 ? "triangle" : "double_triangle";
    }

    if (!w.target && !sc.regions.empty()) {
        const FrameWorld first = model.world_at(0, 0);
        std::array<double, 9> h0 = plane_homography(cam, first), ht = plane_homography(cam, w);
        Mat3 m0, m0i, mt;
        std::copy(h0.begin(), h0.end(), m0.m);
        std::copy(ht.begin(), ht.end(), mt.m);
        invert(m0, m0i);
        const Mat3 hf = mt * m0i;
        const std::string change = model.endoscope.change_at(t);
        for (const RegionSpec& rs : sc.regions) {
            RegionTruth rt;
            rt.id = rs.id;
            for (const auto& uv : rs.polygon_mm) {
                Px p;
                double du = 0, dv = 0;
                if (w.deform > 0) model.displace(uv[0], uv[1], w.deform, du, dv);
                display(cam, w.po + (uv[0] + du) * w.pe1 + (uv[1] + dv) * w.pe2, p);
                rt.polygon_px.push_back(p);
            }
            for (int k = 0; k < 9; ++k) rt.h_from_first[k] = hf.m[k] / hf.m[8];
            double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
            for (const auto& uv : rs.polygon_mm)
                u0 = std::min(u0, uv[0]), u1 = std::max(u1, uv[0]), v0 = std::min(v0, uv[1]),
                v1 = std::max(v1, uv[1]);
            int inside = 0, seen = 0, blocked = 0;
            RegionSpec one = rs;
            for (int a = 0; a < 16; ++a)
                for (int b = 0; b < 16; ++b) {
                    const double u = u0 + (u1 - u0) * (a + 0.5) / 16,
                                 v = v0 + (v1 - v0) * (b + 0.5) / 16;
                    bool in = false;
                    const auto& p = rs.polygon_mm;
                    for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
                        if ((p[i][1] > v) != (p[j][1] > v) &&
                            u < (p[j][0] - p[i][0]) * (v - p[i][1]) / (p[j][1] - p[i][1]) + p[i][0])
                            in = !in;
                    if (!in) continue;
                    ++inside;
                    const Vec3 x = w.po + u * w.pe1 + v * w.pe2;
                    if (!in_view(cam, x)) continue;
                    if (point_visible(w, cam, x, 0.01, -1))
                        ++seen;
                    else
                        ++blocked;
                }
            rt.visible_fraction = inside > 0 ? static_cast<double>(seen) / inside : 0.0;
            rt.change = change == "none" && blocked > 0.05 * std::max(1, seen + blocked)
                            ? "occlusion"
                            : change;
            if (rt.change == "none" && w.deform > 0) rt.change = "deformation";
            out.regions.push_back(rt);
        }
    }

    if (w.target) {
        const TargetSpec& ts = sc.target;
        TargetTruth& tg = out.target;
        out.has_target = true;
        static const char* kinds[] = {"none",         "white",   "squares",
                                      "checkerboard", "two_dot", "grid_lines"};
        tg.kind = kinds[static_cast<int>(ts.kind)];
        tg.distance_mm = w.target_z;
        auto add = [&](double u, double v) {
            tg.points_mm.push_back(w.po + u * w.pe1 + v * w.pe2);
        };
        if (ts.kind == TargetKind::kSquares) {
            for (int j = 0; j < ts.rows; ++j)
                for (int i = 0; i < ts.cols; ++i)
                    add((i - (ts.cols - 1) / 2.0) * ts.pitch_mm,
                        (j - (ts.rows - 1) / 2.0) * ts.pitch_mm);
        } else if (ts.kind == TargetKind::kCheckerboard) {
            for (int j = 1; j <= ts.rows; ++j)
                for (int i = 1; i <= ts.cols; ++i)
                    add((i - (ts.cols + 1) / 2.0) * ts.pitch_mm,
                        (j - (ts.rows + 1) / 2.0) * ts.pitch_mm);
        } else if (ts.kind == TargetKind::kTwoDot) {
            add(-ts.separation_mm / 2, 0);
            add(ts.separation_mm / 2, 0);
        } else if (ts.kind == TargetKind::kGridLines) {
            for (int j = -ts.rows / 2; j <= ts.rows / 2; ++j)
                for (int i = -ts.cols / 2; i <= ts.cols / 2; ++i)
                    add(i * ts.pitch_mm, j * ts.pitch_mm);
        }
        for (const Vec3& p : tg.points_mm) {
            Px d;
            display(cam, p, d);
            tg.points_px.push_back(d);
            tg.points_px_u.push_back(undistorted(cam, p));
        }
    }
}

}  // namespace detail

namespace {

using json = nlohmann::ordered_json;

double r4(double v) {
    return std::round(v * 1e4) / 1e4;
}
json px(Px p) {
    return json::array({r4(p.x), r4(p.y)});
}
json mm(Vec3 v) {
    return json::array({r4(v.x), r4(v.y), r4(v.z)});
}
json dir(Vec3 v) {
    return json::array(
        {std::round(v.x * 1e7) / 1e7, std::round(v.y * 1e7) / 1e7, std::round(v.z * 1e7) / 1e7});
}
json arr(const double* v, int n) {
    json a = json::array();
    for (int i = 0; i < n; ++i) a.push_back(r4(v[i]));
    return a;
}

std::string light_band(double l) {
    return l < 0.30 ? "0-30" : l < 0.455 ? "30-45" : "46-100";
}
std::string speed_class(double s) {
    return s < 4 ? "0-4" : s <= 8 ? "4-8" : ">8";
}

}  // namespace

std::string truth_json_line(const FrameTruth& t, const CameraModel& cam, const Scenario& sc) {
    json j;
    j["frame"] = t.frame;
    j["t_ns"] = t.t_ns;
    json c;
    c["width"] = cam.width;
    c["height"] = cam.height;
    c["fx"] = cam.fx;
    c["fy"] = cam.fy;
    c["cx"] = cam.cx;
    c["cy"] = cam.cy;
    c["distortion"] = {{"model", "odd_radial"}, {"k", cam.k}};
    c["fov"] = {{"cx", cam.fov_cx}, {"cy", cam.fov_cy}, {"radius", cam.fov_radius}};
    j["camera"] = c;
    j["light"] = r4(t.light);
    j["speed_cm_s"] = r4(t.speed_cm_s);
    json tools = json::array();
    for (const ToolTruth& tt : t.tools) {
        json o;
        o["id"] = tt.id;
        o["visible"] = tt.visible;
        o["visible_fraction"] = r4(tt.visible_fraction);
        o["tip_px"] = px(tt.tip_px);
        o["tip_px_undistorted"] = px(tt.tip_px_u);
        o["head_px"] = px(tt.head_px);
        o["head_px_undistorted"] = px(tt.head_px_u);
        o["axis_deg"] = r4(tt.axis_deg);
        o["width_px"] = r4(tt.width_px);
        o["edges_px"] = json::array({arr(tt.edges_px[0].data(), 4), arr(tt.edges_px[1].data(), 4)});
        o["midline_px"] = arr(tt.midline_px.data(), 4);
        o["tip_mm"] = mm(tt.tip_mm);
        o["head_mm"] = mm(tt.head_mm);
        o["axis_dir"] = dir(tt.axis_dir);
        o["pivot_mm"] = mm(tt.pivot_mm);
        o["yaw_deg"] = r4(tt.yaw_deg);
        o["pitch_deg"] = r4(tt.pitch_deg);
        o["roll_deg"] = r4(tt.roll_deg);
        o["diameter_mm"] = tt.diameter_mm;
        o["tip_type"] = tt.tip_type;
        o["jaw"] = tt.jaw;
        o["gesture"] = tt.gesture;
        json markers = json::array();
        for (const MarkerTruth& m : tt.markers) {
            json corners = json::array();
            for (const Px& p : m.corners_px) corners.push_back(px(p));
            markers.push_back({{"strip", m.strip},
                               {"center_px", px(m.center_px)},
                               {"corners_px", corners},
                               {"center_mm", mm(m.center_mm)},
                               {"visible", m.visible}});
        }
        o["markers"] = markers;
        tools.push_back(o);
    }
    j["tools"] = tools;
    j["gesture"] = t.gesture.empty() ? json(nullptr) : json(t.gesture);
    json regions = json::array();
    for (const RegionTruth& r : t.regions) {
        json poly = json::array();
        for (const Px& p : r.polygon_px) poly.push_back(px(p));
        json h = json::array();
        for (double v : r.h_from_first) h.push_back(v);
        regions.push_back({{"id", r.id},
                           {"polygon_px", poly},
                           {"H_from_first", h},
                           {"visible_fraction", r4(r.visible_fraction)},
                           {"change", r.change}});
    }
    j["regions"] = regions;
    j["events"] = t.events;
    json factors = json::object();
    for (const auto& [k, v] : sc.factors) {
        if (const auto* s = std::get_if<std::string>(&v))
            factors[k] = *s;
        else if (const auto* d = std::get_if<double>(&v))
            factors[k] = *d;
        else
            factors[k] = std::get<bool>(v);
    }
    // Levels the scenario does not state are read off the frame.
    if (!factors.contains("speed")) factors["speed"] = speed_class(t.speed_cm_s);
    if (!factors.contains("light")) factors["light"] = light_band(t.light);
    if (!factors.contains("distractors")) factors["distractors"] = !sc.distractors.empty();
    if (!factors.contains("occlusion")) factors["occlusion"] = !sc.occluders.empty();
    j["factors"] = factors;
    if (t.has_target) {
        json pts_mm = json::array(), pts = json::array(), pts_u = json::array();
        for (const Vec3& p : t.target.points_mm) pts_mm.push_back(mm(p));
        for (const Px& p : t.target.points_px) pts.push_back(px(p));
        for (const Px& p : t.target.points_px_u) pts_u.push_back(px(p));
        j["target"] = {{"kind", t.target.kind},
                       {"distance_mm", r4(t.target.distance_mm)},
                       {"points_mm", pts_mm},
                       {"points_px", pts},
                       {"points_px_undistorted", pts_u}};
    } else {
        j["target"] = nullptr;
    }
    return j.dump();
}

}  // namespace endotower::scene
