#include <cmath>

#include "endotower/eval/gesture_metrics.hpp"
#include "endotower/eval/truth.hpp"
#include "json_fields.hpp"

namespace endotower::eval {

using namespace detail;

namespace {

bool parse_tool(const json& t, const std::string& p, TruthTool& tool, std::string& error) {
    if (!t.is_object()) {
        error = "field '" + p.substr(0, p.size() - 1) + "' must be an object";
        return false;
    }
    if (!get_int(t, p, "id", tool.id, error) || !get_bool(t, p, "visible", tool.visible, error) ||
        !get_point(t, p, "tip_px", tool.tip_px, error) ||
        !get_number(t, p, "axis_deg", tool.axis_deg, error) ||
        !get_number(t, p, "width_px", tool.width_px, error) ||
        !opt_number(t, p, "visible_fraction", tool.visible_fraction, error) ||
        !opt_point3(t, p, "tip_mm", tool.tip_mm, error))
        return false;
    if (!(tool.width_px > 0) && tool.visible) {
        error = "field '" + p + "width_px' must be > 0 for a visible tool";
        return false;
    }
    if (t.contains("head_px")) {
        if (!get_point(t, p, "head_px", tool.head_px, error)) return false;
        tool.has_head = true;
    }
    if (auto it = t.find("gesture"); it != t.end() && !it->is_null()) {
        if (!it->is_string() || gesture_index(it->get<std::string>()) < 0) {
            error = "field '" + p + "gesture' must be a gesture label (open_grasper, ...)";
            return false;
        }
        tool.gesture = it->get<std::string>();
    }
    if (t.contains("markers")) {
        const json* markers = nullptr;
        if (!get_array(t, p, "markers", markers, error)) return false;
        for (std::size_t i = 0; i < markers->size(); ++i) {
            const json& m = (*markers)[i];
            const std::string q = p + "markers[" + std::to_string(i) + "].";
            if (!m.is_object()) {
                error = "field '" + q.substr(0, q.size() - 1) + "' must be an object";
                return false;
            }
            TruthMarker marker;
            std::optional<Point3> mm;
            if (!get_int(m, q, "strip", marker.strip, error) ||
                !get_point(m, q, "center_px", marker.center_px, error) ||
                !opt_point3(m, q, "center_mm", mm, error) || !get_bool(m, q, "visible", marker.visible, error))
                return false;
            if (!mm) {
                error = "missing field '" + q + "center_mm'";
                return false;
            }
            marker.center_mm = *mm;
            tool.markers.push_back(marker);
        }
    }
    return true;
}

bool parse_region(const json& r, const std::string& p, TruthRegion& region, std::string& error) {
    if (!r.is_object()) {
        error = "field '" + p.substr(0, p.size() - 1) + "' must be an object";
        return false;
    }
    if (!get_int(r, p, "id", region.id, error) ||
        !get_polygon(r, p, "polygon_px", region.polygon_px, error))
        return false;
    if (auto it = r.find("change"); it != r.end()) {
        if (!it->is_string()) {
            error = "field '" + p + "change' must be a string";
            return false;
        }
        region.change = it->get<std::string>();
    }
    return true;
}

bool parse_factors(const json& j, TruthFrame& f, std::string& error) {
    auto it = j.find("factors");
    if (it == j.end() || it->is_null()) return true;
    if (!it->is_object()) {
        error = "field 'factors' must be an object";
        return false;
    }
    for (const auto& [k, v] : it->items()) {
        std::string level;
        if (v.is_string()) level = v.get<std::string>();
        else if (v.is_boolean()) level = v.get<bool>() ? "yes" : "no";
        else if (v.is_number()) level = v.dump();
        else {
            error = "field 'factors." + k + "' must be a string, number or true/false";
            return false;
        }
        f.factors.emplace_back(k, level);
    }
    return true;
}

}  // namespace

bool parse_truth_line(const std::string& line, TruthFrame& f, std::string& error) {
    json j;
    if (!parse_object(line, j, error)) return false;
    f = TruthFrame{};
    const json* tools = nullptr;
    if (!get_int64(j, "", "frame", f.frame, error) || !get_array(j, "", "tools", tools, error) ||
        !opt_number(j, "", "light", f.light, error) ||
        !opt_number(j, "", "speed_cm_s", f.speed_cm_s, error))
        return false;
    for (std::size_t i = 0; i < tools->size(); ++i) {
        TruthTool t;
        if (!parse_tool((*tools)[i], "tools[" + std::to_string(i) + "].", t, error)) return false;
        f.tools.push_back(std::move(t));
    }
    if (auto it = j.find("gesture"); it != j.end() && !it->is_null()) {
        if (!it->is_string() || gesture_index(it->get<std::string>()) < 0) {
            error = "field 'gesture' must be null or a gesture label (cross, triangle, ...)";
            return false;
        }
        if (it->get<std::string>() != "none") f.gesture = it->get<std::string>();
    }
    if (j.contains("regions")) {
        const json* regions = nullptr;
        if (!get_array(j, "", "regions", regions, error)) return false;
        for (std::size_t i = 0; i < regions->size(); ++i) {
            TruthRegion r;
            if (!parse_region((*regions)[i], "regions[" + std::to_string(i) + "].", r, error))
                return false;
            f.regions.push_back(std::move(r));
        }
    }
    if (j.contains("events")) {
        const json* events = nullptr;
        if (!get_array(j, "", "events", events, error)) return false;
        for (const json& e : *events) {
            if (!e.is_string()) {
                error = "field 'events' must be an array of strings";
                return false;
            }
            f.events.push_back(e.get<std::string>());
        }
    }
    return parse_factors(j, f, error);
}

bool read_truth(const std::string& path, std::vector<TruthFrame>& out, std::string& error) {
    out.clear();
    return for_each_line(
        path, "ground truth",
        [&](const std::string& line, std::string& e) {
            TruthFrame f;
            if (!parse_truth_line(line, f, e)) return false;
            if (!out.empty() && f.frame <= out.back().frame) {
                e = "field 'frame' must increase from line to line (" + std::to_string(f.frame) +
                    " after " + std::to_string(out.back().frame) + ")";
                return false;
            }
            out.push_back(std::move(f));
            return true;
        },
        error);
}

}  // namespace endotower::eval
