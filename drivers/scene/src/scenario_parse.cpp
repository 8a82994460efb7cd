// Scenario YAML reader: every field checked, errors as "FILE:LINE: FIELD: message".
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>

#include "endotower/scene/scenario.hpp"

namespace endotower::scene {

namespace {

class Reader {
public:
    explicit Reader(std::string file) : file_(std::move(file)) {}
    const std::string& error() const { return error_; }

    bool fail(const YAML::Node& n, const std::string& field, const std::string& msg) {
        if (error_.empty()) {
            const int line = n.IsDefined() ? n.Mark().line + 1 : 0;
            error_ = file_ + ":" + std::to_string(line > 0 ? line : 1) + ": " + field + ": " + msg;
        }
        return false;
    }

    // A map whose keys all belong to `allowed`.
    bool map(const YAML::Node& n, const std::string& field,
             std::initializer_list<const char*> allowed) {
        if (!n.IsMap())
            return fail(n, field.empty() ? "scenario" : field, "expected a map of fields");
        for (const auto& kv : n) {
            const std::string key = kv.first.Scalar();
            bool ok = false;
            for (const char* a : allowed) ok = ok || key == a;
            if (!ok) return fail(kv.first, join(field, key), "unknown field");
        }
        return true;
    }

    bool number(const YAML::Node& n, const std::string& field, double& out, double lo, double hi) {
        if (!n.IsScalar()) return fail(n, field, "expected a number");
        const std::string& s = n.Scalar();
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        if (s.empty() || end == nullptr || *end != 0 || !std::isfinite(v))
            return fail(n, field, "expected a number, got '" + s + "'");
        if (v < lo || v > hi) {
            return fail(n, field, "must be in " + show(lo) + ".." + show(hi) + ", got " + s);
        }
        out = v;
        return true;
    }

    bool integer(const YAML::Node& n, const std::string& field, int& out, int lo, int hi) {
        double v = 0;
        if (!number(n, field, v, lo, hi)) return false;
        if (v != std::floor(v)) return fail(n, field, "expected a whole number, got " + n.Scalar());
        out = static_cast<int>(v);
        return true;
    }

    bool text(const YAML::Node& n, const std::string& field, std::string& out) {
        if (!n.IsScalar()) return fail(n, field, "expected text");
        out = n.Scalar();
        return true;
    }

    bool boolean(const YAML::Node& n, const std::string& field, bool& out) {
        const std::string s = n.IsScalar() ? n.Scalar() : "";
        if (s == "true")
            out = true;
        else if (s == "false")
            out = false;
        else
            return fail(n, field, "expected true or false");
        return true;
    }

    bool numbers(const YAML::Node& n, const std::string& field, double* out, std::size_t count,
                 double lo, double hi) {
        if (!n.IsSequence() || n.size() != count)
            return fail(n, field, "expected a list of " + std::to_string(count) + " numbers");
        for (std::size_t i = 0; i < count; ++i)
            if (!number(n[i], field + "[" + std::to_string(i) + "]", out[i], lo, hi)) return false;
        return true;
    }

    bool vec3(const YAML::Node& n, const std::string& field, Vec3& v) {
        double a[3];
        if (!numbers(n, field, a, 3, -1e4, 1e4)) return false;
        v = {a[0], a[1], a[2]};
        return true;
    }

    template <typename E>
    bool choice(const YAML::Node& n, const std::string& field, E& out,
                std::initializer_list<std::pair<const char*, E>> options) {
        std::string s, names;
        if (!text(n, field, s)) return false;
        for (const auto& [name, value] : options) {
            if (s == name) {
                out = value;
                return true;
            }
            names += names.empty() ? name : std::string(", ") + name;
        }
        return fail(n, field, "expected one of " + names + ", got '" + s + "'");
    }

    static std::string show(double v) {
        if (v == std::floor(v) && std::abs(v) < 1e15)
            return std::to_string(static_cast<long long>(v));
        std::ostringstream s;
        s << v;
        return s.str();
    }

    static std::string join(const std::string& a, const std::string& b) {
        return a.empty() ? b : a + "." + b;
    }

private:
    std::string file_, error_;
};

std::string at(const std::string& f, std::size_t i) {
    return f + "[" + std::to_string(i) + "]";
}

bool parse_camera(Reader& r, const YAML::Node& n, CameraSpec& c) {
    if (!r.map(
            n, "camera",
            {"focal", "sy_over_sx", "center_offset", "k", "fov_radius", "vignetting", "blur_px"}))
        return false;
    if (n["focal"] && !r.number(n["focal"], "camera.focal", c.focal, 0.2, 5)) return false;
    if (n["sy_over_sx"] && !r.number(n["sy_over_sx"], "camera.sy_over_sx", c.sy_over_sx, 0.5, 2))
        return false;
    if (n["center_offset"] &&
        !r.numbers(n["center_offset"], "camera.center_offset", c.center_offset, 2, -0.2, 0.2))
        return false;
    if (n["k"]) {
        const YAML::Node& k = n["k"];
        if (!k.IsSequence() || k.size() > 4)
            return r.fail(k, "camera.k", "expected a list of up to 4 numbers");
        c.k.assign(k.size(), 0.0);
        for (std::size_t i = 0; i < k.size(); ++i)
            if (!r.number(k[i], at("camera.k", i), c.k[i], -5, 5)) return false;
    }
    if (n["fov_radius"] && !r.number(n["fov_radius"], "camera.fov_radius", c.fov_radius, 0.1, 2))
        return false;
    if (n["vignetting"] && !r.number(n["vignetting"], "camera.vignetting", c.vignetting, 0, 1))
        return false;
    if (n["blur_px"] && !r.number(n["blur_px"], "camera.blur_px", c.blur_px, 0, 5)) return false;
    return true;
}

bool parse_tissue(Reader& r, const YAML::Node& n, TissueSpec& t, const std::string& dir) {
    if (!r.map(n, "tissue",
               {"distance_mm", "tilt_deg", "vessels", "fat", "wetness", "blood", "image"}))
        return false;
    if (n["distance_mm"] &&
        !r.number(n["distance_mm"], "tissue.distance_mm", t.distance_mm, 10, 1000))
        return false;
    if (n["tilt_deg"] && !r.numbers(n["tilt_deg"], "tissue.tilt_deg", t.tilt_deg, 2, -70, 70))
        return false;
    const std::pair<const char*, double*> amounts[] = {
        {"vessels", &t.vessels}, {"fat", &t.fat}, {"wetness", &t.wetness}, {"blood", &t.blood}};
    for (const auto& [key, dst] : amounts)
        if (n[key] && !r.number(n[key], std::string("tissue.") + key, *dst, 0, 1)) return false;
    if (n["image"]) {
        if (!r.text(n["image"], "tissue.image", t.image)) return false;
        std::filesystem::path p(t.image);
        if (p.is_relative()) p = std::filesystem::path(dir) / p;
        t.image = p.lexically_normal().string();
        if (!std::filesystem::is_regular_file(p))
            return r.fail(n["image"], "tissue.image", "no such file: " + t.image);
    }
    return true;
}

bool parse_target(Reader& r, const YAML::Node& n, TargetSpec& t) {
    if (!r.map(n, "target",
               {"kind", "pitch_mm", "size_mm", "line_mm", "dot_mm", "separation_mm", "cols", "rows",
                "distances_mm", "frames_per_distance", "offset_mm"}))
        return false;
    if (!n["kind"]) return r.fail(n, "target.kind", "missing");
    if (!r.choice(n["kind"], "target.kind", t.kind,
                  {{"white", TargetKind::kWhite},
                   {"squares", TargetKind::kSquares},
                   {"checkerboard", TargetKind::kCheckerboard},
                   {"two_dot", TargetKind::kTwoDot},
                   {"grid_lines", TargetKind::kGridLines}}))
        return false;
    const std::pair<const char*, double*> mm[] = {{"pitch_mm", &t.pitch_mm},
                                                  {"size_mm", &t.size_mm},
                                                  {"line_mm", &t.line_mm},
                                                  {"dot_mm", &t.dot_mm},
                                                  {"separation_mm", &t.separation_mm}};
    for (const auto& [key, dst] : mm)
        if (n[key] && !r.number(n[key], std::string("target.") + key, *dst, 0.1, 200)) return false;
    if (n["cols"] && !r.integer(n["cols"], "target.cols", t.cols, 2, 40)) return false;
    if (n["rows"] && !r.integer(n["rows"], "target.rows", t.rows, 2, 40)) return false;
    if (n["distances_mm"]) {
        const YAML::Node& d = n["distances_mm"];
        t.distances_mm.clear();
        if (d.IsScalar()) {
            t.distances_mm.push_back(0);
            if (!r.number(d, "target.distances_mm", t.distances_mm[0], 10, 1000)) return false;
        } else if (d.IsSequence() && d.size() > 0) {
            t.distances_mm.assign(d.size(), 0);
            for (std::size_t i = 0; i < d.size(); ++i)
                if (!r.number(d[i], at("target.distances_mm", i), t.distances_mm[i], 10, 1000))
                    return false;
        } else {
            return r.fail(d, "target.distances_mm", "expected a number or a list of numbers");
        }
    }
    if (n["frames_per_distance"]) {
        const YAML::Node& d = n["frames_per_distance"];
        const std::string f = "target.frames_per_distance";
        if (d.IsScalar()) {
            t.frames_per_distance = {0};
            if (!r.number(d, f, t.frames_per_distance[0], 1, 1e5)) return false;
        } else if (d.IsSequence() && d.size() == t.distances_mm.size()) {
            t.frames_per_distance.assign(d.size(), 0);
            for (std::size_t i = 0; i < d.size(); ++i)
                if (!r.number(d[i], at(f, i), t.frames_per_distance[i], 1, 1e5)) return false;
        } else {
            return r.fail(d, f,
                          "expected a number or one number per distance (" +
                              std::to_string(t.distances_mm.size()) + ")");
        }
    }
    if (n["offset_mm"] && !r.numbers(n["offset_mm"], "target.offset_mm", t.offset_mm, 2, -200, 200))
        return false;
    return true;
}

bool parse_jaw(Reader& r, const YAML::Node& n, const std::string& f, Jaw& j) {
    return r.choice(n, f, j, {{"open", Jaw::kOpen}, {"closed", Jaw::kClosed}});
}
bool parse_material(Reader& r, const YAML::Node& n, const std::string& f, Material& m) {
    return r.choice(n, f, m, {{"dark", Material::kDark}, {"metal", Material::kMetal}});
}
bool parse_anchor(Reader& r, const YAML::Node& n, const std::string& f, Anchor& a) {
    return r.choice(n, f, a,
                    {{"tip", Anchor::kTip}, {"head", Anchor::kHead}, {"marker", Anchor::kMarker}});
}

bool parse_segment(Reader& r, const YAML::Node& n, const std::string& f, Segment& s) {
    if (!r.map(n, f,
               {"move", "pose", "dwell", "loop", "wander", "speed_cm_s", "frames", "anchor",
                "roll_deg", "jaw", "box_mm"}))
        return false;
    int verbs = 0;
    for (const char* v : {"move", "pose", "dwell", "loop", "wander"}) verbs += n[v] ? 1 : 0;
    if (verbs != 1) return r.fail(n, f, "expected exactly one of move, pose, dwell, loop, wander");
    if (n["speed_cm_s"] && !r.number(n["speed_cm_s"], f + ".speed_cm_s", s.speed_cm_s, 0.01, 200))
        return false;
    if (n["frames"] && !r.number(n["frames"], f + ".frames", s.frames, 0, 1e6)) return false;
    if (n["anchor"] && !parse_anchor(r, n["anchor"], f + ".anchor", s.anchor)) return false;
    if (n["roll_deg"]) {
        double v = 0;
        if (!r.number(n["roll_deg"], f + ".roll_deg", v, -360, 360)) return false;
        s.roll_deg = v;
    }
    if (n["jaw"]) {
        Jaw j{};
        if (!parse_jaw(r, n["jaw"], f + ".jaw", j)) return false;
        s.jaw = j;
    }
    if (n["box_mm"] && !r.number(n["box_mm"], f + ".box_mm", s.box_mm, 0.5, 200)) return false;
    const bool timed = n["speed_cm_s"] || n["frames"];
    if (n["move"]) {
        s.type = SegmentType::kMove;
        if (!r.vec3(n["move"], f + ".move", s.to)) return false;
        if (!timed) return r.fail(n, f, "a move needs speed_cm_s or frames");
    } else if (n["pose"]) {
        s.type = SegmentType::kPose;
        const YAML::Node& p = n["pose"];
        if (!r.map(p, f + ".pose", {"yaw_deg", "pitch_deg", "depth_mm"})) return false;
        for (const char* k : {"yaw_deg", "pitch_deg", "depth_mm"})
            if (!p[k]) return r.fail(p, f + ".pose." + k, "missing");
        if (!r.number(p["yaw_deg"], f + ".pose.yaw_deg", s.yaw_deg, -89, 89) ||
            !r.number(p["pitch_deg"], f + ".pose.pitch_deg", s.pitch_deg, -89, 89) ||
            !r.number(p["depth_mm"], f + ".pose.depth_mm", s.depth_mm, 1, 500))
            return false;
    } else if (n["dwell"]) {
        s.type = SegmentType::kDwell;
        if (!r.number(n["dwell"], f + ".dwell", s.frames, 1, 1e6)) return false;
    } else if (n["loop"]) {
        s.type = SegmentType::kLoop;
        const YAML::Node& l = n["loop"];
        if (!r.map(l, f + ".loop", {"radius_mm", "turns"})) return false;
        if (l["radius_mm"] &&
            !r.number(l["radius_mm"], f + ".loop.radius_mm", s.radius_mm, 0.5, 100))
            return false;
        if (l["turns"] && !r.number(l["turns"], f + ".loop.turns", s.turns, 0.1, 100)) return false;
        if (!timed) return r.fail(n, f, "a loop needs speed_cm_s or frames");
    } else {
        s.type = SegmentType::kWander;
        if (!r.number(n["wander"], f + ".wander", s.frames, 1, 1e6)) return false;
        if (!n["speed_cm_s"]) return r.fail(n, f, "a wander needs speed_cm_s");
    }
    return true;
}

bool parse_start(Reader& r, const YAML::Node& n, const std::string& f, ToolSpec& t) {
    if (!r.map(n, f, {"tip_mm", "head_mm", "marker_mm", "yaw_deg", "pitch_deg", "depth_mm"}))
        return false;
    const char* points[] = {"tip_mm", "head_mm", "marker_mm"};
    const Anchor anchors[] = {Anchor::kTip, Anchor::kHead, Anchor::kMarker};
    int given = 0;
    for (int i = 0; i < 3; ++i)
        if (n[points[i]]) {
            ++given;
            t.start_anchor = anchors[i];
            if (!r.vec3(n[points[i]], f + "." + points[i], t.start_point)) return false;
        }
    const bool pose = n["yaw_deg"] || n["pitch_deg"] || n["depth_mm"];
    if (given + (pose ? 1 : 0) != 1)
        return r.fail(n, f,
                      "give one of tip_mm, head_mm, marker_mm, or yaw_deg/pitch_deg/depth_mm");
    if (pose) {
        t.start_is_pose = true;
        for (const char* k : {"yaw_deg", "pitch_deg", "depth_mm"})
            if (!n[k]) return r.fail(n, f + "." + k, "missing");
        if (!r.number(n["yaw_deg"], f + ".yaw_deg", t.start_yaw, -89, 89) ||
            !r.number(n["pitch_deg"], f + ".pitch_deg", t.start_pitch, -89, 89) ||
            !r.number(n["depth_mm"], f + ".depth_mm", t.start_depth, 1, 500))
            return false;
    }
    return true;
}

bool parse_tool(Reader& r, const YAML::Node& n, const std::string& f, ToolSpec& t) {
    if (!r.map(n, f,
               {"id", "diameter_mm", "tip", "jaw", "shaft", "pivot_mm", "start", "roll_deg",
                "color", "markers", "motion", "repeat"}))
        return false;
    if (n["id"] && !r.integer(n["id"], f + ".id", t.id, 0, 1000)) return false;
    if (n["diameter_mm"]) {
        if (!r.number(n["diameter_mm"], f + ".diameter_mm", t.diameter_mm, 0, 100)) return false;
        if (t.diameter_mm != 5 && t.diameter_mm != 10)
            return r.fail(n["diameter_mm"], f + ".diameter_mm",
                          "expected 5 or 10, got " + n["diameter_mm"].Scalar());
    }
    if (n["tip"] && !r.choice(n["tip"], f + ".tip", t.tip,
                              {{"grasper", TipType::kGrasper}, {"scissors", TipType::kScissors}}))
        return false;
    if (n["jaw"] && !parse_jaw(r, n["jaw"], f + ".jaw", t.jaw)) return false;
    if (n["shaft"] && !parse_material(r, n["shaft"], f + ".shaft", t.shaft)) return false;
    if (n["pivot_mm"] && !r.vec3(n["pivot_mm"], f + ".pivot_mm", t.pivot)) return false;
    if (!n["start"]) return r.fail(n, f + ".start", "missing");
    if (!parse_start(r, n["start"], f + ".start", t)) return false;
    if (n["roll_deg"] && !r.number(n["roll_deg"], f + ".roll_deg", t.roll_deg, -360, 360))
        return false;
    if (n["color"]) {
        std::array<double, 3> c{};
        if (!r.numbers(n["color"], f + ".color", c.data(), 3, 0, 255)) return false;
        t.color = c;
    }
    if (n["markers"]) {
        const YAML::Node& m = n["markers"];
        const std::string mf = f + ".markers";
        if (!r.map(m, mf, {"count", "width_mm", "gap_mm", "offset_mm"})) return false;
        if (m["count"] && !r.integer(m["count"], mf + ".count", t.markers.count, 0, 8))
            return false;
        if (m["width_mm"] &&
            !r.number(m["width_mm"], mf + ".width_mm", t.markers.width_mm, 0.5, 30))
            return false;
        if (m["gap_mm"] && !r.number(m["gap_mm"], mf + ".gap_mm", t.markers.gap_mm, 0.5, 30))
            return false;
        if (m["offset_mm"] &&
            !r.number(m["offset_mm"], mf + ".offset_mm", t.markers.offset_mm, 0, 100))
            return false;
    }
    if (n["repeat"] && !r.boolean(n["repeat"], f + ".repeat", t.repeat)) return false;
    if (n["motion"]) {
        const YAML::Node& m = n["motion"];
        if (!m.IsSequence()) return r.fail(m, f + ".motion", "expected a list of segments");
        t.motion.resize(m.size());
        for (std::size_t i = 0; i < m.size(); ++i)
            if (!parse_segment(r, m[i], at(f + ".motion", i), t.motion[i])) return false;
    }
    const bool uses_marker = t.start_anchor == Anchor::kMarker ||
                             std::any_of(t.motion.begin(), t.motion.end(), [](const Segment& s) {
                                 return s.anchor == Anchor::kMarker;
                             });
    if (uses_marker && t.markers.count == 0)
        return r.fail(n, f + ".markers", "the marker anchor needs markers.count >= 1");
    return true;
}

bool parse_camera_segment(Reader& r, const YAML::Node& n, const std::string& f, CameraSegment& s) {
    if (!r.map(n, f,
               {"translate_mm", "rotate_deg", "zoom", "orbit_deg", "hold", "frames", "change",
                "background"}))
        return false;
    int verbs = 0;
    for (const char* v : {"translate_mm", "rotate_deg", "zoom", "orbit_deg", "hold"})
        verbs += n[v] ? 1 : 0;
    if (verbs != 1)
        return r.fail(n, f,
                      "expected exactly one of translate_mm, rotate_deg, zoom, orbit_deg, hold");
    if (n["frames"] && !r.number(n["frames"], f + ".frames", s.frames, 1, 1e6)) return false;
    if (n["translate_mm"]) {
        s.move = CameraMove::kTranslate;
        if (!r.vec3(n["translate_mm"], f + ".translate_mm", s.by)) return false;
    } else if (n["rotate_deg"]) {
        s.move = CameraMove::kRotate;
        if (!r.number(n["rotate_deg"], f + ".rotate_deg", s.deg, -360, 360)) return false;
    } else if (n["zoom"]) {
        s.move = CameraMove::kZoom;
        if (!r.number(n["zoom"], f + ".zoom", s.zoom, 0.2, 5)) return false;
    } else if (n["orbit_deg"]) {
        s.move = CameraMove::kOrbit;
        if (!r.numbers(n["orbit_deg"], f + ".orbit_deg", s.orbit_deg, 2, -60, 60)) return false;
    } else {
        s.move = CameraMove::kHold;
        if (!r.number(n["hold"], f + ".hold", s.frames, 1, 1e6)) return false;
    }
    if (n["change"] && !r.choice(n["change"], f + ".change", s.change,
                                 {{"translation", std::string("translation")},
                                  {"rotation", std::string("rotation")},
                                  {"zoom_in", std::string("zoom_in")},
                                  {"zoom_out", std::string("zoom_out")},
                                  {"planar", std::string("planar")},
                                  {"background", std::string("background")},
                                  {"occlusion", std::string("occlusion")},
                                  {"viewpoint", std::string("viewpoint")},
                                  {"none", std::string("none")}}))
        return false;
    if (n["background"] && !r.boolean(n["background"], f + ".background", s.background))
        return false;
    return true;
}

bool parse_root(Reader& r, const YAML::Node& root, Scenario& s, const std::string& dir) {
    if (!r.map(root, "", {"name",        "description", "frames",    "fps",     "size",
                          "seed",        "camera",      "tissue",    "target",  "tools",
                          "distractors", "occluders",   "endoscope", "regions", "light",
                          "noise",       "motion_blur", "smoke",     "flashes", "factors",
                          "deformation"}))
        return false;
    if (root["name"] && !r.text(root["name"], "name", s.name)) return false;
    if (root["description"] && !r.text(root["description"], "description", s.description))
        return false;
    if (!root["frames"]) return r.fail(root, "frames", "missing");
    if (!r.integer(root["frames"], "frames", s.frames, 1, 1000000)) return false;
    if (root["fps"] && !r.number(root["fps"], "fps", s.fps, 1, 240)) return false;
    if (root["size"]) {
        std::string v;
        if (!r.text(root["size"], "size", v)) return false;
        if (v == "640x480")
            s.width = 640, s.height = 480;
        else if (v == "1920x1080")
            s.width = 1920, s.height = 1080;
        else
            return r.fail(root["size"], "size", "expected 640x480 or 1920x1080, got '" + v + "'");
    }
    if (root["seed"]) {
        double v = 0;
        if (!r.number(root["seed"], "seed", v, 0, 9007199254740991.0)) return false;
        s.seed = static_cast<std::uint64_t>(v);
    }
    if (root["camera"] && !parse_camera(r, root["camera"], s.camera)) return false;
    if (root["tissue"] && !parse_tissue(r, root["tissue"], s.tissue, dir)) return false;
    if (root["target"] && !parse_target(r, root["target"], s.target)) return false;
    if (root["tools"]) {
        const YAML::Node& t = root["tools"];
        if (!t.IsSequence() || t.size() > 4)
            return r.fail(t, "tools", "expected a list of up to 4 tools");
        s.tools.resize(t.size());
        for (std::size_t i = 0; i < t.size(); ++i) {
            s.tools[i].id = static_cast<int>(i);
            if (!parse_tool(r, t[i], at("tools", i), s.tools[i])) return false;
            for (std::size_t j = 0; j < i; ++j)
                if (s.tools[j].id == s.tools[i].id)
                    return r.fail(t[i], at("tools", i) + ".id",
                                  "duplicate id " + std::to_string(s.tools[i].id));
        }
    }
    if (root["distractors"]) {
        const YAML::Node& d = root["distractors"];
        if (!d.IsSequence()) return r.fail(d, "distractors", "expected a list");
        s.distractors.resize(d.size());
        for (std::size_t i = 0; i < d.size(); ++i) {
            const std::string f = at("distractors", i);
            DistractorSpec& x = s.distractors[i];
            if (!r.map(d[i], f, {"diameter_mm", "material", "from_mm", "to_mm"})) return false;
            if (d[i]["diameter_mm"] &&
                !r.number(d[i]["diameter_mm"], f + ".diameter_mm", x.diameter_mm, 1, 30))
                return false;
            if (d[i]["material"] &&
                !parse_material(r, d[i]["material"], f + ".material", x.material))
                return false;
            if (!d[i]["from_mm"]) return r.fail(d[i], f + ".from_mm", "missing");
            for (const char* key : {"from_mm", "to_mm"}) {
                if (!d[i][key]) continue;
                const YAML::Node& e = d[i][key];
                Vec3* dst = std::string(key) == "from_mm" ? x.from : x.to;
                if (!e.IsSequence() || e.size() != 2)
                    return r.fail(e, f + "." + key, "expected two end points [[x,y,z],[x,y,z]]");
                if (!r.vec3(e[0], f + "." + key + "[0]", dst[0]) ||
                    !r.vec3(e[1], f + "." + key + "[1]", dst[1]))
                    return false;
            }
            if (!d[i]["to_mm"]) x.to[0] = x.from[0], x.to[1] = x.from[1];
        }
    }
    if (root["occluders"]) {
        const YAML::Node& o = root["occluders"];
        if (!o.IsSequence()) return r.fail(o, "occluders", "expected a list");
        s.occluders.resize(o.size());
        for (std::size_t i = 0; i < o.size(); ++i) {
            const std::string f = at("occluders", i);
            OccluderSpec& x = s.occluders[i];
            if (!r.map(o[i], f, {"center_mm", "to_mm", "radius_mm"})) return false;
            if (!o[i]["center_mm"]) return r.fail(o[i], f + ".center_mm", "missing");
            if (!r.vec3(o[i]["center_mm"], f + ".center_mm", x.from)) return false;
            x.to = x.from;
            if (o[i]["to_mm"] && !r.vec3(o[i]["to_mm"], f + ".to_mm", x.to)) return false;
            if (o[i]["radius_mm"] &&
                !r.numbers(o[i]["radius_mm"], f + ".radius_mm", x.radius_mm, 2, 0.5, 200))
                return false;
            if (x.from.z <= 1 || x.to.z <= 1)
                return r.fail(o[i], f + ".center_mm", "z must be > 1 mm");
        }
    }
    if (root["endoscope"]) {
        const YAML::Node& e = root["endoscope"];
        if (!e.IsSequence()) return r.fail(e, "endoscope", "expected a list of motions");
        s.endoscope.resize(e.size());
        for (std::size_t i = 0; i < e.size(); ++i)
            if (!parse_camera_segment(r, e[i], at("endoscope", i), s.endoscope[i])) return false;
    }
    if (root["regions"]) {
        const YAML::Node& g = root["regions"];
        if (!g.IsSequence()) return r.fail(g, "regions", "expected a list");
        s.regions.resize(g.size());
        for (std::size_t i = 0; i < g.size(); ++i) {
            const std::string f = at("regions", i);
            RegionSpec& x = s.regions[i];
            x.id = static_cast<int>(i);
            if (!r.map(g[i], f, {"id", "polygon_mm"})) return false;
            if (g[i]["id"] && !r.integer(g[i]["id"], f + ".id", x.id, 0, 1000)) return false;
            const YAML::Node& p = g[i]["polygon_mm"];
            if (!p || !p.IsSequence() || p.size() < 3)
                return r.fail(p ? p : g[i], f + ".polygon_mm",
                              "expected a list of at least 3 [u, v] points");
            x.polygon_mm.resize(p.size());
            for (std::size_t j = 0; j < p.size(); ++j)
                if (!r.numbers(p[j], at(f + ".polygon_mm", j), x.polygon_mm[j].data(), 2, -500,
                               500))
                    return false;
        }
    }
    if (root["deformation"]) {
        const YAML::Node& d = root["deformation"];
        DeformationSpec& x = s.deformation;
        if (!r.map(d, "deformation", {"center_mm", "radius_mm", "push_mm", "from_frame", "frames"}))
            return false;
        if (!d["push_mm"]) return r.fail(d, "deformation.push_mm", "missing");
        if ((d["center_mm"] && !r.numbers(d["center_mm"], "deformation.center_mm", x.center_mm, 2, -500, 500)) ||
            (d["radius_mm"] && !r.number(d["radius_mm"], "deformation.radius_mm", x.radius_mm, 1, 500)) ||
            !r.numbers(d["push_mm"], "deformation.push_mm", x.push_mm, 2, -100, 100) ||
            (d["from_frame"] && !r.number(d["from_frame"], "deformation.from_frame", x.from_frame, 0, 1e6)) ||
            (d["frames"] && !r.number(d["frames"], "deformation.frames", x.frames, 1, 1e6)))
            return false;
        // The inverse mapping (a fixed point) needs the displacement's slope below 1.
        if (std::hypot(x.push_mm[0], x.push_mm[1]) >= 1.6 * x.radius_mm)
            return r.fail(d["push_mm"], "deformation.push_mm",
                          "a push of 1.6 x radius_mm or more folds the tissue over itself");
    }
    if (root["light"]) {
        const YAML::Node& l = root["light"];
        if (l.IsMap()) {
            if (!r.map(l, "light", {"from", "to"})) return false;
            if (!l["from"] || !l["to"]) return r.fail(l, "light", "a ramp needs from and to");
            if (!r.number(l["from"], "light.from", s.light_from, 0, 1) ||
                !r.number(l["to"], "light.to", s.light_to, 0, 1))
                return false;
        } else {
            if (!r.number(l, "light", s.light_from, 0, 1)) return false;
            s.light_to = s.light_from;
        }
    }
    if (root["noise"] && !r.number(root["noise"], "noise", s.noise, 0, 50)) return false;
    if (root["motion_blur"] && !r.number(root["motion_blur"], "motion_blur", s.motion_blur, 0, 1))
        return false;
    if (root["smoke"]) {
        const YAML::Node& m = root["smoke"];
        if (m.IsMap()) {
            if (!r.map(m, "smoke", {"density", "from_frame"})) return false;
            if (m["density"] && !r.number(m["density"], "smoke.density", s.smoke, 0, 1))
                return false;
            if (m["from_frame"] &&
                !r.number(m["from_frame"], "smoke.from_frame", s.smoke_from_frame, 0, 1e6))
                return false;
        } else if (!r.number(m, "smoke", s.smoke, 0, 1)) {
            return false;
        }
    }
    if (root["flashes"] && !r.number(root["flashes"], "flashes", s.flash_rate, 0, 1)) return false;
    if (root["factors"]) {
        const YAML::Node& fa = root["factors"];
        if (!fa.IsMap()) return r.fail(fa, "factors", "expected a map of names to values");
        for (const auto& kv : fa) {
            const std::string key = kv.first.Scalar(), f = "factors." + key;
            if (!kv.second.IsScalar())
                return r.fail(kv.second, f, "expected text, a number or true/false");
            const std::string v = kv.second.Scalar();
            char* end = nullptr;
            const double d = std::strtod(v.c_str(), &end);
            if (v == "true" || v == "false")
                s.factors.emplace_back(key, v == "true");
            else if (!v.empty() && *end == 0 && std::isfinite(d) && kv.second.Tag() != "!")
                s.factors.emplace_back(key, d);
            else
                s.factors.emplace_back(key, v);
        }
    }
    return true;
}

}  // namespace

bool parse_scenario(const std::string& text, const std::string& name, Scenario& out,
                    std::string& error) {
    Reader r(name);
    Scenario s;
    s.path = name;
    YAML::Node root;
    try {
        root = YAML::Load(text);
    } catch (const YAML::Exception& e) {
        error =
            name + ":" + std::to_string(e.mark.line + 1) + ": scenario: not valid YAML: " + e.msg;
        return false;
    }
    const std::string dir = std::filesystem::path(name).parent_path().string();
    bool ok = false;
    try {
        ok = parse_root(r, root, s, dir);
    } catch (const YAML::Exception& e) {
        error = name + ":" + std::to_string(e.mark.line + 1) + ": scenario: " + e.msg;
        return false;
    }
    if (!ok) {
        error = r.error();
        return false;
    }
    if (s.name.empty()) s.name = std::filesystem::path(name).stem().string();
    out = std::move(s);
    return true;
}

bool load_scenario(const std::string& path, Scenario& out, std::string& error) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        error = path + ": cannot open the scenario file";
        return false;
    }
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) {
        error = path + ": cannot read the scenario file";
        return false;
    }
    return parse_scenario(text.str(), path, out, error);
}

void scale_durations(Scenario& s, double scale) {
    s.frames = std::max(1, static_cast<int>(std::lround(s.frames * scale)));
    for (double& f : s.target.frames_per_distance) f *= scale;
    for (ToolSpec& t : s.tools)
        for (Segment& g : t.motion)
            if (g.speed_cm_s <= 0 || g.type == SegmentType::kWander) g.frames *= scale;
    for (CameraSegment& c : s.endoscope) c.frames *= scale;
    s.smoke_from_frame *= scale;
}

}  // namespace endotower::scene
