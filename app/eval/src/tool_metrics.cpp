#include "endotower/eval/tool_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <unordered_map>

#include "endotower/eval/assignment.hpp"

namespace endotower::eval {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

double dist(Point2 a, Point2 b) { return std::hypot(a.x - b.x, a.y - b.y); }
double dist3(Point3 a, Point3 b) {
    return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
}

// What the rules compare, per annotated/true tool in one frame.
struct Target {
    int id = 0;
    Point2 point;
    double axis_deg = 0, tolerance_px = 0;
    bool axis_as_line = false;
    std::optional<Point3> tip_mm;
};

// Assigns `tools` to `targets` and appends one pair per target; returns the number
// of trace tools left unassigned (false positives).
int score_frame(std::int64_t frame, const std::vector<Target>& targets,
                const std::vector<TraceTool>& tools, bool use_head, const ToolRule& rule,
                std::vector<ToolPair>& pairs) {
    const int rows = static_cast<int>(targets.size()), cols = static_cast<int>(tools.size());
    std::vector<double> cost(static_cast<std::size_t>(rows) * cols);
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c)
            cost[r * cols + c] = dist(targets[r].point, use_head ? tools[c].head_px : tools[c].tip_px);
    const std::vector<int> match = assign_min_cost(cost, rows, cols);
    int assigned = 0;
    for (int r = 0; r < rows; ++r) {
        const Target& t = targets[r];
        ToolPair p;
        p.frame = frame;
        p.truth_id = t.id;
        p.tolerance_px = t.tolerance_px;
        if (match[r] >= 0) {
            const TraceTool& tool = tools[match[r]];
            ++assigned;
            p.trace_id = tool.id;
            p.error_px = cost[r * cols + match[r]];
            p.axis_error_deg = t.axis_as_line ? line_diff_deg(t.axis_deg, tool.axis_deg)
                                              : direction_diff_deg(t.axis_deg, tool.axis_deg);
            p.success = p.error_px <= p.tolerance_px && p.axis_error_deg <= rule.max_axis_deg;
            if (t.tip_mm && tool.tip_mm) p.error_mm = dist3(*t.tip_mm, *tool.tip_mm);
        }
        pairs.push_back(p);
    }
    return cols - assigned;
}

// Totals, errors and identity from the pairs.
void summarise(ToolScore& s) {
    std::vector<double> px, mm;
    std::map<int, std::map<int, int>> ids;  // truth id -> trace id -> successful pairs
    for (const ToolPair& p : s.pairs) {
        ++s.tool_frames;
        if (p.error_px < 0) continue;  // no trace tool assigned
        ++s.matched;
        px.push_back(p.error_px);
        if (p.error_mm) mm.push_back(*p.error_mm);
        if (p.success) {
            ++s.successes;
            ++ids[p.truth_id][p.trace_id];
        }
    }
    s.success_rate = s.tool_frames > 0 ? static_cast<double>(s.successes) / s.tool_frames : 0;
    s.mean_error_px = mean_of(px);
    s.p95_error_px = percentile_nearest_rank(px, 95);
    s.with_mm = static_cast<int>(mm.size());
    s.mean_error_mm = mean_of(mm);
    s.p95_error_mm = percentile_nearest_rank(mm, 95);
    s.false_positives_per_frame = s.frames > 0 ? static_cast<double>(s.false_positives) / s.frames : 0;
    std::set<int> truth_ids;
    for (const ToolPair& p : s.pairs) truth_ids.insert(p.truth_id);
    if (s.point == "tip" && truth_ids.size() >= 2 && s.successes > 0) {
        int consistent = 0;
        for (const auto& [truth_id, counts] : ids) {
            int best = 0;
            for (const auto& [trace_id, n] : counts) best = std::max(best, n);
            consistent += best;
        }
        s.identity_pairs = s.successes;
        s.identity_consistency = static_cast<double>(consistent) / s.successes;
    }
}

}  // namespace

ToolScore score_tools(const std::vector<TruthFrame>& truth, const std::vector<AnalysisFrame>& trace,
                      const ToolRule& rule) {
    ToolScore s;
    s.point = "tip";
    std::unordered_map<std::int64_t, const AnalysisFrame*> by_frame;
    for (const AnalysisFrame& a : trace) by_frame[a.frame] = &a;
    struct Acc {
        LevelScore level;
        double error_sum = 0;
    };
    std::map<std::pair<std::string, std::string>, Acc> levels;
    const std::vector<TraceTool> none;
    for (const TruthFrame& f : truth) {
        ++s.frames;
        auto it = by_frame.find(f.frame);
        if (it == by_frame.end()) ++s.frames_without_trace;
        const std::vector<TraceTool>& tools = it != by_frame.end() ? it->second->tools : none;
        std::vector<Target> targets;
        for (const TruthTool& t : f.tools) {
            if (!t.visible) continue;
            targets.push_back({t.id, t.tip_px, t.axis_deg, rule.width_factor * t.width_px, false, t.tip_mm});
        }
        const std::size_t first = s.pairs.size();
        s.false_positives += score_frame(f.frame, targets, tools, false, rule, s.pairs);
        for (const auto& [factor, level] : f.factors) {
            Acc& a = levels[{factor, level}];
            a.level.factor = factor;
            a.level.level = level;
            for (std::size_t i = first; i < s.pairs.size(); ++i) {
                const ToolPair& p = s.pairs[i];
                ++a.level.tool_frames;
                if (p.error_px < 0) continue;  // no trace tool assigned
                ++a.level.matched;
                a.error_sum += p.error_px;
                if (p.success) ++a.level.successes;
            }
        }
    }
    for (auto& [key, a] : levels) {
        a.level.mean_error_px = a.level.matched > 0 ? a.error_sum / a.level.matched : 0;
        s.levels.push_back(a.level);
    }
    summarise(s);
    return s;
}

ToolScore score_sznitman(const SznitmanAnnotations& truth, const std::vector<AnalysisFrame>& trace,
                         int first_index, const ToolRule& rule) {
    ToolScore s;
    s.point = "head";
    std::unordered_map<std::int64_t, const AnalysisFrame*> by_frame;
    for (const AnalysisFrame& a : trace) by_frame[a.frame] = &a;
    const std::vector<TraceTool> none;
    for (const SznitmanFrame& f : truth.frames) {
        ++s.frames;
        const std::int64_t frame = static_cast<std::int64_t>(f.index) - first_index;
        auto it = by_frame.find(frame);
        if (it == by_frame.end()) ++s.frames_without_trace;
        const std::vector<TraceTool>& tools = it != by_frame.end() ? it->second->tools : none;
        std::vector<Target> targets;
        for (std::size_t i = 0; i < f.tools.size(); ++i) {
            const SznitmanTool& t = f.tools[i];
            targets.push_back({static_cast<int>(i), t.head(), t.angle_rad * kRadToDeg,
                               rule.head_scale_factor * t.scale, true, std::nullopt});
        }
        s.false_positives += score_frame(f.index, targets, tools, true, rule, s.pairs);
    }
    summarise(s);
    return s;
}

}  // namespace endotower::eval
