// The console summary and the markdown report (tables in the book's layouts).
#include <map>
#include <set>

#include "endotower/eval/report.hpp"
#include "report_common.hpp"

namespace endotower::eval {

using detail::fmt;
using detail::pct;

namespace {

std::string rule_text(const EvalResult& r) {
    return r.sznitman ? "head within 0.5 x SCALE of the annotated head and axis within 20 deg "
                        "(as lines)"
                      : "tip within 2 x tool width and axis within 20 deg (book ch. 4)";
}

std::string value_text(const ThresholdCheck& c) {
    if (!c.value) return "n/a";
    const bool fraction = c.name.find("rate") != std::string::npos ||
                          c.name.find("consistency") != std::string::npos ||
                          c.name.find("fraction") != std::string::npos;
    return fraction ? pct(*c.value) + " %" : fmt("%.3f", *c.value);
}
std::string limit_text(const ThresholdCheck& c) {
    ThresholdCheck l = c;
    l.value = c.limit;
    return value_text(l);
}

// Per tool id (truth mode) or per annotation slot: successes and tool-frames.
std::map<int, std::pair<int, int>> per_tool(const ToolScore& s) {
    std::map<int, std::pair<int, int>> out;
    for (const ToolPair& p : s.pairs) {
        auto& [ok, n] = out[p.truth_id];
        ok += p.success ? 1 : 0;
        ++n;
    }
    return out;
}

}  // namespace

std::string render_summary(const EvalResult& r, const std::vector<ThresholdCheck>& checks) {
    const ToolScore& s = r.tools;
    std::string o = "endotower eval: " + r.trace_path + " against " + r.truth_path + "\n";
    o += fmt("tools (%s): %d tool-frames in %d frames", rule_text(r).c_str(), s.tool_frames, s.frames);
    if (!r.has_tools) o += " (the trace has no 'tools' member)";
    o += "\n  success " + pct(s.success_rate) + fmt(" %% (%d/%d)", s.successes, s.tool_frames);
    o += fmt("; %s error mean %.2f px, p95 %.2f px over %d matched", s.point.c_str(), s.mean_error_px,
             s.p95_error_px, s.matched);
    if (s.with_mm > 0) o += fmt("; 3-D tip error mean %.2f mm, p95 %.2f mm (%d)", s.mean_error_mm, s.p95_error_mm, s.with_mm);
    o += fmt("\n  false positives %.3f per frame (%d)", s.false_positives_per_frame, s.false_positives);
    if (s.identity_consistency) o += "; identity consistency " + pct(*s.identity_consistency) + " %";
    if (s.frames_without_trace > 0) o += fmt("; %d frames have no trace line", s.frames_without_trace);
    o += "\n";
    std::string factor;
    for (const LevelScore& l : detail::ordered_levels(s.levels)) {
        if (l.factor != factor) {
            o += (factor.empty() ? "  " : "\n  ") + detail::factor_title(l.factor) + ":";
            factor = l.factor;
        }
        o += fmt(" %s %s %% (%d)", l.level.c_str(),
                 pct(l.tool_frames ? static_cast<double>(l.successes) / l.tool_frames : 0).c_str(),
                 l.tool_frames);
    }
    if (!factor.empty()) o += "\n";
    if (r.gestures.present) {
        const GestureScore& g = r.gestures;
        o += fmt("gestures: %d trials, %d recognized", g.trials, g.correct_trials);
        if (g.overall_rate()) o += " (" + pct(*g.overall_rate()) + " %)";
        if (g.frames > 0)
            o += fmt("; frame accuracy %s %% (%d/%d)",
                     pct(static_cast<double>(g.correct_frames) / g.frames).c_str(), g.correct_frames, g.frames);
        o += "\n";
    }
    if (r.regions.present) {
        const RegionScore& g = r.regions;
        o += fmt("regions: %d region-frames: GOOD %d, OK %d, FAIL %d", g.good + g.ok + g.fail, g.good, g.ok, g.fail);
        if (g.with_corners > 0) o += fmt("; mean corner error %.2f px", g.mean_corner_error_px);
        o += "\n";
    }
    for (const ThresholdCheck& c : checks)
        o += "threshold: " + c.name + " " + value_text(c) + " " + c.op + " " + limit_text(c) +
             (c.pass ? " PASS" : " FAIL") + "\n";
    return o;
}

std::string render_markdown(const EvalResult& r, const std::vector<ThresholdCheck>& checks) {
    const ToolScore& s = r.tools;
    std::string o = "# Evaluation report\n\n";
    o += "- trace: `" + r.trace_path + "`\n- " + (r.sznitman ? "annotations" : "ground truth") + ": `" +
         r.truth_path + "`\n- success rule: " + rule_text(r) + "\n";
    o += "- definitions: docs/evaluation.md\n\n";
    if (!checks.empty()) {
        bool all = true;
        for (const ThresholdCheck& c : checks) all = all && c.pass;
        o += std::string("## Thresholds: ") + (all ? "PASS" : "FAIL") + "\n\n| check | value | limit | result |\n|---|---|---|---|\n";
        for (const ThresholdCheck& c : checks)
            o += "| " + c.name + " | " + value_text(c) + " | " + c.op + " " + limit_text(c) + " | " +
                 (c.pass ? "PASS" : "**FAIL**") + " |\n";
        o += "\n";
    }
    o += "## Tool tracking\n\n| metric | value |\n|---|---|\n";
    o += fmt("| frames | %d |\n| tool-frames | %d |\n", s.frames, s.tool_frames);
    o += "| success rate | " + pct(s.success_rate) + fmt(" %% (%d/%d) |\n", s.successes, s.tool_frames);
    o += fmt("| matched tool-frames | %d |\n", s.matched);
    o += fmt("| mean %s error | %.2f px |\n| p95 %s error | %.2f px |\n", s.point.c_str(), s.mean_error_px,
             s.point.c_str(), s.p95_error_px);
    if (s.with_mm > 0)
        o += fmt("| mean 3-D tip error | %.2f mm (%d) |\n| p95 3-D tip error | %.2f mm |\n", s.mean_error_mm,
                 s.with_mm, s.p95_error_mm);
    o += fmt("| false positives | %d (%.3f per frame) |\n", s.false_positives, s.false_positives_per_frame);
    if (s.identity_consistency)
        o += "| identity consistency | " + pct(*s.identity_consistency) + fmt(" %% of %d successful pairs |\n", s.identity_pairs);
    if (s.frames_without_trace > 0) o += fmt("| frames without a trace line | %d |\n", s.frames_without_trace);
    o += s.tool_frames > 0 ? "\n![error over time](tip_error.png)\n\n" : "\n";
    if (!s.levels.empty()) {
        o += "### Success per input factor (layout of table 4.1)\n\n"
             "| Input factors | Range | Rate of success (%) | tool-frames | mean error (px) |\n|---|---|---|---|---|\n";
        std::string factor;
        for (const LevelScore& l : detail::ordered_levels(s.levels)) {
            const std::string title = l.factor != factor ? detail::factor_title(l.factor) : "";
            factor = l.factor;
            o += "| " + title + " | " + l.level + " | " +
                 pct(l.tool_frames ? static_cast<double>(l.successes) / l.tool_frames : 0) +
                 fmt(" | %d | %.2f |\n", l.tool_frames, l.mean_error_px);
        }
        o += "\n![success per factor](success_by_factor.png)\n\n";
    }
    o += fmt("### Tracking success rate per tool (layout of tables 4.2/5.1)\n\n"
             "| %s | Tracking success rate (frames/N frames x 100%%) |\n|---|---|\n",
             r.sznitman ? "Annotation slot" : "Tool");
    for (const auto& [id, c] : per_tool(s))
        o += fmt("| %s %d | %s |\n", r.sznitman ? "slot" : "tool", id,
                 c.first == 0 ? "Fail" : (pct(static_cast<double>(c.first) / c.second) + fmt("%% (%d/%d)", c.first, c.second)).c_str());
    o += "\n";
    if (r.gestures.present) {
        const GestureScore& g = r.gestures;
        o += "## Gestures (layout of table 3.3)\n\nPerformed (rows) against recognized (columns), in trials.\n\n| Performed |";
        for (int c = 0; c < kGestureCount; ++c) o += fmt(" %s |", gesture_title(c).c_str());
        o += " Recognition rate (%) |\n|---|";
        for (int c = 0; c <= kGestureCount; ++c) o += "---|";
        o += "\n";
        for (int p = 0; p < kGestureCount; ++p) {
            o += fmt("| %s |", gesture_title(p).c_str());
            for (int c = 0; c < kGestureCount; ++c) o += fmt(" %d |", g.counts[p][c]);
            o += fmt(" %s |\n", g.rate(p) ? pct(*g.rate(p)).c_str() : "-");
        }
        o += fmt("\n%d trials, %d recognized", g.trials, g.correct_trials);
        if (g.overall_rate()) o += " (" + pct(*g.overall_rate()) + " %)";
        if (g.frames > 0) o += fmt("; frame accuracy %s %%", pct(static_cast<double>(g.correct_frames) / g.frames).c_str());
        o += ".\n\n![gesture confusion](gesture_confusion.png)\n\n";
    }
    if (r.regions.present) {
        const RegionScore& g = r.regions;
        o += "## Regions (GOOD / OK / FAIL, book ch. 6)\n\n| Change | GOOD | OK | FAIL | Result (most frequent) |\n|---|---|---|---|---|\n";
        for (const auto& [change, c] : g.by_change) {
            const int best = c[0] >= c[1] && c[0] >= c[2] ? 0 : c[1] >= c[2] ? 1 : 2;
            o += fmt("| %s | %d | %d | %d | %s |\n", change.c_str(), c[0], c[1], c[2],
                     region_class_name(static_cast<RegionClass>(best)));
        }
        o += fmt("| **all** | %d | %d | %d | |\n\n", g.good, g.ok, g.fail);
        if (g.with_corners > 0) o += fmt("Mean corner error %.2f px over %d region-frames.\n\n", g.mean_corner_error_px, g.with_corners);
        o += "![regions](regions.png)\n\n";
    }
    return o;
}

}  // namespace endotower::eval
