#include "board_config.hpp"

#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>

#include "endotower/sci/sci_menu.hpp"
#include "endotower/v4l2/capture_format.hpp"
#include "endotower/vision/anchored_overlay.hpp"
#include "endotower/vision/tool_tracker_factory.hpp"

namespace endotower::firmware {

namespace {

namespace fs = std::filesystem;

struct Reader {
    const std::string& file;
    std::string& error;

    bool fail(const YAML::Node& n, const std::string& field, const std::string& what) {
        const int line = n.Mark().line >= 0 ? n.Mark().line + 1 : 0;
        error = file + ":" + std::to_string(line) + ": field '" + field + "': " + what;
        return false;
    }

    // Only the listed keys are allowed in a mapping.
    bool keys(const YAML::Node& map, const std::string& prefix,
              std::initializer_list<const char*> allowed) {
        if (!map.IsMap()) return fail(map, prefix, "expected a mapping of keys");
        for (const auto& kv : map) {
            // YAML allows any node as a key ("? [a, b]: c"); a board file does not.
            if (!kv.first.IsScalar())
                return fail(kv.first, prefix.empty() ? "(top level)" : prefix,
                            "a key must be a plain name");
            const std::string k = kv.first.Scalar();
            bool ok = false;
            for (const char* a : allowed) ok = ok || k == a;
            if (!ok) {
                std::string list;
                for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
                return fail(kv.first, prefix.empty() ? k : prefix + "." + k,
                            "unknown key (expected one of: " + list + ")");
            }
        }
        return true;
    }

    bool text(const YAML::Node& map, const char* key, const std::string& field, std::string& out) {
        const YAML::Node n = map[key];
        if (!n) return true;
        if (!n.IsScalar()) return fail(n, field, "expected a string");
        out = n.Scalar();
        return true;
    }

    // A file the appliance reads (media, calibration, model; issue 10): a relative path
    // must stay inside the board file's directory, through ".." and symlinks alike, so
    // a hostile board cannot reach "../../etc/..."; an absolute path is the installer's
    // explicit choice (the service sees a read-only system, endotower.service).
    bool confined(const YAML::Node& map, const char* key, const std::string& field,
                  std::string& out) {
        if (!text(map, key, field, out)) return false;
        if (out.empty() || fs::path(out).is_absolute()) return true;
        std::error_code ec;
        const fs::path base = fs::weakly_canonical(fs::absolute(file, ec).parent_path(), ec);
        const fs::path target = fs::weakly_canonical(base / out, ec);
        const fs::path rel = target.lexically_relative(base);
        if (!ec && !rel.empty() && *rel.begin() != "..") return true;
        return fail(map[key], field,
                    "'" + out + "' leads out of the board file's directory " + base.string() +
                        " (relative paths must stay inside it; give an absolute path instead)");
    }

    bool number(const YAML::Node& map, const char* key, const std::string& field, double lo,
                double hi, double& out) {
        const YAML::Node n = map[key];
        if (!n) return true;
        double v = 0;
        std::istringstream s(n.IsScalar() ? n.Scalar() : std::string());
        s.imbue(std::locale::classic());
        if (!n.IsScalar() || !(s >> v) || !(s >> std::ws).eof())
            return fail(n, field,
                        "expected a number, got '" + (n.IsScalar() ? n.Scalar() : "?") + "'");
        if (v < lo || v > hi) {
            std::ostringstream m;
            m << "must be between " << lo << " and " << hi << ", got " << n.Scalar();
            return fail(n, field, m.str());
        }
        out = v;
        return true;
    }

    bool integer(const YAML::Node& map, const char* key, const std::string& field, int lo, int hi,
                 int& out) {
        double v = out;
        if (!number(map, key, field, lo, hi, v)) return false;
        if (map[key] && v != static_cast<int>(v))
            return fail(map[key], field, "expected an integer");
        out = static_cast<int>(v);
        return true;
    }

    // A 16-bit id, written 0x1209 or 4617.
    bool id16(const YAML::Node& map, const char* key, const std::string& field, int& out) {
        const YAML::Node n = map[key];
        if (!n) return true;
        const std::string t = n.IsScalar() ? n.Scalar() : std::string();
        const bool hex = t.size() > 2 && t[0] == '0' && (t[1] == 'x' || t[1] == 'X');
        std::size_t used = 0;
        long v = -1;
        try {
            v = std::stol(t, &used, hex ? 16 : 10);
        } catch (const std::exception&) {
            used = 0;
        }
        if (t.empty() || used != t.size() || v < 0 || v > 0xffff)
            return fail(n, field,
                        "expected a 16-bit id like 0x1209, got '" + (n.IsScalar() ? t : "?") + "'");
        out = static_cast<int>(v);
        return true;
    }

    bool boolean(const YAML::Node& map, const char* key, const std::string& field, bool& out) {
        const YAML::Node n = map[key];
        if (!n) return true;
        if (!n.IsScalar() || !YAML::convert<bool>::decode(n, out))
            return fail(n, field,
                        "expected true or false, got '" + (n.IsScalar() ? n.Scalar() : "?") + "'");
        return true;
    }
};

// "1920x1080@60" or "1920x1080@59.94" (the refresh may be left out: 60).
bool parse_mode(const std::string& text, int& w, int& h, double& hz) {
    char x = 0, at = 0;
    std::istringstream s(text);
    s.imbue(std::locale::classic());
    hz = 60.0;
    if (!(s >> w >> x >> h) || x != 'x' || w < 64 || h < 64 || w > 8192 || h > 8192) return false;
    if (s >> at) {
        if (at != '@' || !(s >> hz) || hz < 1 || hz > 500) return false;
    }
    return (s >> std::ws).eof();
}

std::string resolve(const fs::path& base, const std::string& p) {
    if (p.empty() || fs::path(p).is_absolute()) return p;
    return (base / p).lexically_normal().string();
}

// capture:, button:, handle: (issue 9's input drivers).
bool load_input_devices(Reader& r, const YAML::Node& root, BoardConfig& c) {
    if (const YAML::Node n = root["capture"]) {
        auto& k = c.capture;
        k.present = true;
        if (!r.keys(
                n, "capture",
                {"device", "format", "width", "height", "fps", "buffers", "input", "dv_timings"}) ||
            !r.text(n, "device", "capture.device", k.device) ||
            !r.text(n, "format", "capture.format", k.format) ||
            !r.integer(n, "width", "capture.width", 16, 8192, k.width) ||
            !r.integer(n, "height", "capture.height", 16, 8192, k.height) ||
            !r.number(n, "fps", "capture.fps", 0, 1000, k.fps) ||
            !r.integer(n, "buffers", "capture.buffers", 2, 16, k.buffers) ||
            !r.integer(n, "input", "capture.input", -1, 255, k.input) ||
            !r.text(n, "dv_timings", "capture.dv_timings", k.dv_timings))
            return false;
        v4l2::CaptureFormat f{};
        if (!v4l2::parse_capture_format(k.format, f))
            return r.fail(
                n["format"], "capture.format",
                "unknown format '" + k.format + "' (expected yuyv, uyvy, nv12, bgrx or mjpeg)");
        if (!v4l2::info(f).supported)
            return r.fail(n["format"], "capture.format", std::string(v4l2::info(f).why));
        v4l2::DvTimingsName dv;
        if (!k.dv_timings.empty() && k.dv_timings != "query" &&
            !v4l2::parse_dv_timings_name(k.dv_timings, dv))
            return r.fail(
                n["dv_timings"], "capture.dv_timings",
                "expected query or timings like 1920x1080p60, got '" + k.dv_timings + "'");
        if (k.device.empty()) return r.fail(n, "capture.device", "must name the video device");
    }
    if (const YAML::Node n = root["button"]) {
        auto& b = c.button;
        b.present = true;
        if (!r.keys(n, "button", {"chip", "line", "active_low", "debounce_ms", "long_press_ms"}) ||
            !r.text(n, "chip", "button.chip", b.chip) ||
            !r.integer(n, "line", "button.line", 0, 511, b.line) ||
            !r.boolean(n, "active_low", "button.active_low", b.active_low) ||
            !r.number(n, "debounce_ms", "button.debounce_ms", 0, 1000, b.debounce_ms) ||
            !r.number(n, "long_press_ms", "button.long_press_ms", 0, 60000, b.long_press_ms))
            return false;
        if (b.chip.empty())
            return r.fail(n, "button.chip", "missing (gpiochip name, label or number)");
    }
    if (const YAML::Node n = root["handle"]) {
        auto& h = c.handle;
        h.present = true;
        if (!r.keys(n, "handle", {"vid", "pid", "serial", "usage_page"}) ||
            !r.id16(n, "vid", "handle.vid", h.vid) || !r.id16(n, "pid", "handle.pid", h.pid) ||
            !r.text(n, "serial", "handle.serial", h.serial) ||
            !r.id16(n, "usage_page", "handle.usage_page", h.usage_page))
            return false;
        if (!n["vid"] || !n["pid"]) return r.fail(n, "handle", "vid and pid are required");
    }
    return true;
}

}  // namespace

bool load_board(const std::string& path, BoardConfig& out, std::string& error) {
    std::ifstream in(path);
    if (!in) {
        error = "board file not found or unreadable: " + path;
        return false;
    }
    YAML::Node root;
    try {
        root = YAML::Load(in);
    } catch (const YAML::ParserException& e) {
        error = path + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg;
        return false;
    }
    Reader r{path, error};
    BoardConfig c;
    c.path = path;
    if (!root || root.IsNull()) {
        error = path + ": board file is empty";
        return false;
    }
    if (!r.keys(root, "",
                {"board", "description", "video", "analysis", "sim", "capture", "button", "handle",
                 "calibration", "display", "paths", "sci"}))
        return false;
    if (!root["board"]) return r.fail(root, "board", "missing (the board's name)");
    if (!r.text(root, "board", "board", c.name) ||
        !r.text(root, "description", "description", c.description))
        return false;
    if (!r.confined(root, "calibration", "calibration", c.calibration)) return false;
    if (const YAML::Node v = root["video"]) {
        if (!r.keys(
                v, "video",
                {"latency_ms", "compose_budget_ms", "late_tolerance_ms", "latency_budget_ms"}) ||
            !r.number(v, "latency_budget_ms", "video.latency_budget_ms", 0, 10000,
                      c.latency_budget_ms) ||
            !r.number(v, "late_tolerance_ms", "video.late_tolerance_ms", 0, 1000,
                      c.late_tolerance_ms) ||
            !r.number(v, "latency_ms", "video.latency_ms", 0, 1000, c.latency_ms) ||
            !r.number(v, "compose_budget_ms", "video.compose_budget_ms", 0, 1000,
                      c.compose_budget_ms))
            return false;
    }
    if (const YAML::Node a = root["analysis"]) {
        if (!r.keys(a, "analysis",
                    {"stage", "tracker", "tool_model", "tool_diameter_mm", "timeout_ms",
                     "virtual_cost_ms", "max_overlay_age", "regions", "gestures", "markers",
                     "fov_mask"}) ||
            !r.text(a, "stage", "analysis.stage", c.stage) ||
            !r.text(a, "tracker", "analysis.tracker", c.tracker) ||
            !r.confined(a, "tool_model", "analysis.tool_model", c.tool_model) ||
            !r.number(a, "tool_diameter_mm", "analysis.tool_diameter_mm", 1, 20,
                      c.tool_diameter_mm) ||
            !r.number(a, "timeout_ms", "analysis.timeout_ms", 0, 60000, c.analysis_timeout_ms) ||
            !r.number(a, "virtual_cost_ms", "analysis.virtual_cost_ms", 0, 60000,
                      c.analysis_virtual_cost_ms) ||
            !r.integer(a, "max_overlay_age", "analysis.max_overlay_age", 0, 1000,
                       c.max_overlay_age) ||
            !r.boolean(a, "markers", "analysis.markers", c.markers) ||
            !r.boolean(a, "fov_mask", "analysis.fov_mask", c.fov_mask))
            return false;
        if (c.stage != "status_badge" && c.stage != "none")
            return r.fail(a["stage"], "analysis.stage",
                          "unknown stage '" + c.stage + "' (expected status_badge or none)");
        if (c.tracker != "none" && c.tracker != "kalman" && c.tracker != "kalman_red" &&
            c.tracker != "likelihood" && !vision::is_book_tracker(c.tracker)) {
            std::string names;
            for (std::string_view n : vision::book_tracker_names()) names += ", " + std::string(n);
            return r.fail(a["tracker"], "analysis.tracker",
                          "unknown tracker '" + c.tracker +
                              "' (expected none, kalman, kalman_red, likelihood" + names + ")");
        }
        if (c.tracker == "likelihood" && c.tool_model.empty())
            return r.fail(a["tracker"], "analysis.tracker",
                          "the likelihood tracker needs analysis.tool_model (a file of 'endotower "
                          "train-tool-model')");
        if (const YAML::Node g = a["gestures"]) {
            if (!g.IsMap())
                return r.fail(g, "analysis.gestures",
                              "expected a map {model: FILE, tool_model: FILE, hold_ms: N}");
            if (!r.keys(g, "analysis.gestures", {"model", "tool_model", "hold_ms"}) ||
                !r.confined(g, "model", "analysis.gestures.model", c.gesture_model) ||
                !r.confined(g, "tool_model", "analysis.gestures.tool_model",
                            c.gesture_tool_model) ||
                !r.number(g, "hold_ms", "analysis.gestures.hold_ms", 0, 60000, c.gesture_hold_ms))
                return false;
            if (c.gesture_model.empty())
                return r.fail(g, "analysis.gestures.model",
                              "missing (a file of 'endotower train-gestures')");
            c.gestures = true;
        }
    }
    const YAML::Node analysis = root["analysis"];  // checked to be a mapping above
    if (const YAML::Node g = analysis ? analysis["regions"] : analysis) {
        if (!r.keys(g, "analysis.regions",
                    {"descriptor", "redetect_interval", "min_inliers", "detect_max_width",
                     "propagate", "mark_with_tool", "overlay", "depth_mm", "media"}) ||
            !r.text(g, "overlay", "analysis.regions.overlay", c.region_overlay) ||
            !r.number(g, "depth_mm", "analysis.regions.depth_mm", 5, 500, c.region_depth_mm) ||
            !r.confined(g, "media", "analysis.regions.media", c.region_media) ||
            !r.text(g, "descriptor", "analysis.regions.descriptor", c.region_descriptor) ||
            !r.integer(g, "redetect_interval", "analysis.regions.redetect_interval", 0, 1000,
                       c.region_redetect_interval) ||
            !r.integer(g, "min_inliers", "analysis.regions.min_inliers", 4, 1000,
                       c.region_min_inliers) ||
            !r.integer(g, "detect_max_width", "analysis.regions.detect_max_width", 160, 8192,
                       c.region_detect_max_width) ||
            !r.boolean(g, "propagate", "analysis.regions.propagate", c.region_propagate) ||
            !r.boolean(g, "mark_with_tool", "analysis.regions.mark_with_tool",
                       c.region_mark_with_tool))
            return false;
        if (c.region_descriptor != "sift" && c.region_descriptor != "orb" &&
            c.region_descriptor != "akaze")
            return r.fail(
                g["descriptor"], "analysis.regions.descriptor",
                "unknown descriptor '" + c.region_descriptor +
                    "' (expected sift, orb or akaze; SURF is patented and not in Debian's OpenCV)");
    }
    if (const YAML::Node s = root["sim"]) {
        if (!r.keys(s, "sim",
                    {"input", "events", "output", "frames", "trace", "realtime", "fps"}) ||
            !r.confined(s, "input", "sim.input", c.sim_input) ||
            !r.confined(s, "events", "sim.events", c.sim_events) ||
            !r.text(s, "output", "sim.output", c.sim_output) ||
            !r.text(s, "frames", "sim.frames", c.sim_frames) ||
            !r.text(s, "trace", "sim.trace", c.sim_trace) ||
            !r.boolean(s, "realtime", "sim.realtime", c.sim_realtime) ||
            !r.number(s, "fps", "sim.fps", 0, 1000, c.sim_fps))
            return false;
    }
    if (const YAML::Node d = root["display"]) {
        std::string mode;
        if (!r.keys(d, "display", {"card", "connector", "mode", "zero_copy", "atomic"}) ||
            !r.text(d, "card", "display.card", c.display_card) ||
            !r.text(d, "connector", "display.connector", c.display_connector) ||
            !r.text(d, "mode", "display.mode", mode) ||
            !r.boolean(d, "zero_copy", "display.zero_copy", c.display_zero_copy) ||
            !r.boolean(d, "atomic", "display.atomic", c.display_atomic))
            return false;
        if (!mode.empty() &&
            !parse_mode(mode, c.display_width, c.display_height, c.display_refresh_hz))
            return r.fail(d["mode"], "display.mode",
                          "expected WIDTHxHEIGHT@HZ (e.g. 1920x1080@60), got '" + mode + "'");
        if (c.display_card.empty())
            return r.fail(d["card"], "display.card", "must name a device, e.g. /dev/dri/card0");
    }
    if (const YAML::Node p = root["paths"]) {
        if (!r.keys(p, "paths", {"storage"}) || !r.text(p, "storage", "paths.storage", c.storage))
            return false;
    }
    if (const YAML::Node n = root["sci"]) {
        if (!r.keys(n, "sci",
                    {"layout", "dwell_ms", "activation_hold_ms", "cross_hold_ms", "confirm_ms",
                     "media", "patient_record"}) ||
            !r.text(n, "layout", "sci.layout", c.sci_layout) ||
            !r.number(n, "dwell_ms", "sci.dwell_ms", 100, 60000, c.sci_dwell_ms) ||
            !r.number(n, "activation_hold_ms", "sci.activation_hold_ms", 100, 60000,
                      c.sci_activation_hold_ms) ||
            !r.number(n, "cross_hold_ms", "sci.cross_hold_ms", 100, 60000, c.sci_cross_hold_ms) ||
            !r.number(n, "confirm_ms", "sci.confirm_ms", 100, 60000, c.sci_confirm_ms) ||
            !r.confined(n, "media", "sci.media", c.sci_media) ||
            !r.confined(n, "patient_record", "sci.patient_record", c.sci_patient_record))
            return false;
        sci::SciLayout layout;
        if (!sci::parse_sci_layout(c.sci_layout, layout))
            return r.fail(
                n["layout"], "sci.layout",
                "unknown layout '" + c.sci_layout + "' (expected buttons, ring or three_level)");
        c.sci = true;
        if (c.region_mark_with_tool)
            return r.fail(
                analysis["regions"]["mark_with_tool"], "analysis.regions.mark_with_tool",
                "not with sci: (the handle's button drives the interface); mark regions from the "
                "timeline or --region");
    }
    if (const YAML::Node g = analysis ? analysis["regions"] : analysis) {
        vision::RegionOverlay overlay;
        std::string why;
        if (!vision::parse_region_overlay(c.region_overlay, overlay, why))
            return r.fail(g["overlay"], "analysis.regions.overlay", why);
        if (overlay.kind == vision::RegionOverlayKind::kImage && c.region_media.empty() &&
            c.sci_media.empty())
            return r.fail(g["overlay"], "analysis.regions.overlay",
                          "an image needs a media folder (analysis.regions.media or sci.media)");
    }
    if (!load_input_devices(r, root, c)) return false;
    const fs::path base = fs::path(path).parent_path();
    for (std::string* p : {&c.sim_input, &c.sim_events, &c.sim_output, &c.sim_frames, &c.sim_trace,
                           &c.tool_model, &c.calibration, &c.gesture_model, &c.gesture_tool_model,
                           &c.storage, &c.sci_media, &c.sci_patient_record, &c.region_media})
        *p = resolve(base, *p);
    if (c.region_media.empty()) c.region_media = c.sci_media;
    out = std::move(c);
    return true;
}

}  // namespace endotower::firmware
