#include "endotower/eval/analysis_trace.hpp"

#include <set>

#include "endotower/app/trace_reader.hpp"
#include "endotower/eval/gesture_metrics.hpp"
#include "json_fields.hpp"

namespace endotower::eval {

using namespace detail;

namespace {

bool not_object(const std::string& p, std::string& error) {
    error = "field '" + p.substr(0, p.size() - 1) + "' must be an object";
    return false;
}

bool parse_tools(const json& j, AnalysisFrame& f, std::string& error) {
    const json* tools = nullptr;
    if (!get_array(j, "", "tools", tools, error)) return false;
    f.has_tools = true;
    for (std::size_t i = 0; i < tools->size(); ++i) {
        const json& t = (*tools)[i];
        const std::string p = "tools[" + std::to_string(i) + "].";
        if (!t.is_object()) return not_object(p, error);
        TraceTool tool;
        if (!get_int(t, p, "id", tool.id, error) || !get_point(t, p, "tip_px", tool.tip_px, error) ||
            !get_point(t, p, "head_px", tool.head_px, error) ||
            !get_number(t, p, "axis_deg", tool.axis_deg, error) ||
            !get_number(t, p, "confidence", tool.confidence, error) ||
            !opt_point3(t, p, "tip_mm", tool.tip_mm, error))
            return false;
        f.tools.push_back(tool);
    }
    return true;
}

bool parse_gesture(const json& g, AnalysisFrame& f, std::string& error) {
    if (!g.is_object()) return not_object("gesture.", error);
    TraceGesture out;
    auto it = g.find("label");
    if (it == g.end()) {
        error = "missing field 'gesture.label'";
        return false;
    }
    if (!it->is_null()) {
        if (!it->is_string() || gesture_index(it->get<std::string>()) < 0) {
            error = "field 'gesture.label' must be null or a gesture label (open_grasper, "
                    "closed_grasper, open_scissors, closed_scissors, cross, triangle, "
                    "double_triangle)";
            return false;
        }
        if (it->get<std::string>() != "none") out.label = it->get<std::string>();
    }
    if (!get_bool(g, "gesture.", "fired", out.fired, error) ||
        !opt_number(g, "gesture.", "confidence", out.confidence, error) ||
        !opt_number(g, "gesture.", "held_ms", out.held_ms, error))
        return false;
    f.gesture = out;
    return true;
}

bool parse_regions(const json& j, AnalysisFrame& f, std::string& error) {
    const json* regions = nullptr;
    if (!get_array(j, "", "regions", regions, error)) return false;
    f.has_regions = true;
    for (std::size_t i = 0; i < regions->size(); ++i) {
        const json& r = (*regions)[i];
        const std::string p = "regions[" + std::to_string(i) + "].";
        if (!r.is_object()) return not_object(p, error);
        TraceRegion region;
        if (!get_int(r, p, "id", region.id, error) ||
            !get_polygon(r, p, "polygon_px", region.polygon_px, error))
            return false;
        auto st = r.find("state");
        if (st == r.end() || !st->is_string() ||
            (st->get<std::string>() != "tracked" && st->get<std::string>() != "lost")) {
            error = "field '" + p + "state' must be \"tracked\" or \"lost\"";
            return false;
        }
        region.tracked = st->get<std::string>() == "tracked";
        if (r.contains("inliers") && !get_int(r, p, "inliers", region.inliers, error)) return false;
        f.regions.push_back(std::move(region));
    }
    return true;
}

bool parse_markers(const json& j, AnalysisFrame& f, std::string& error) {
    const json* markers = nullptr;
    if (!get_array(j, "", "markers", markers, error)) return false;
    f.has_markers = true;
    for (std::size_t i = 0; i < markers->size(); ++i) {
        const json& m = (*markers)[i];
        const std::string p = "markers[" + std::to_string(i) + "].";
        if (!m.is_object()) return not_object(p, error);
        TraceMarker marker;
        if (!get_point(m, p, "center_px", marker.center_px, error) ||
            !get_number(m, p, "diameter_px", marker.diameter_px, error) ||
            !get_int(m, p, "strips", marker.strips, error) || !opt_point3(m, p, "tip_mm", marker.tip_mm, error))
            return false;
        f.markers.push_back(marker);
    }
    return true;
}

}  // namespace

bool parse_analysis_line(const std::string& line, AnalysisFrame& f, std::string& error) {
    app::TraceRecord record;
    if (!app::parse_trace_line(line, record, error)) return false;
    f = AnalysisFrame{};
    f.frame = record.frame;
    json j;
    if (!parse_object(record.extra, j, error)) return false;
    if (j.contains("tools") && !j["tools"].is_null() && !parse_tools(j, f, error)) return false;
    if (auto it = j.find("gesture"); it != j.end() && !it->is_null() && !parse_gesture(*it, f, error))
        return false;
    if (j.contains("regions") && !j["regions"].is_null() && !parse_regions(j, f, error))
        return false;
    if (j.contains("markers") && !j["markers"].is_null() && !parse_markers(j, f, error)) return false;
    return true;
}

bool read_analysis_trace(const std::string& path, std::vector<AnalysisFrame>& out,
                         std::string& error) {
    out.clear();
    std::set<std::int64_t> seen;
    return for_each_line(
        path, "trace",
        [&](const std::string& line, std::string& e) {
            AnalysisFrame f;
            if (!parse_analysis_line(line, f, e)) return false;
            if (!seen.insert(f.frame).second) {
                e = "field 'frame': frame " + std::to_string(f.frame) + " is listed twice";
                return false;
            }
            out.push_back(std::move(f));
            return true;
        },
        error);
}

}  // namespace endotower::eval
