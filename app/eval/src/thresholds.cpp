#include <algorithm>
#include <cstdlib>
#include <map>

#include "endotower/eval/report.hpp"
#include "report_common.hpp"

namespace endotower::eval {

namespace detail {

std::string factor_title(const std::string& factor) {
    static const std::map<std::string, std::string> kTitles = {
        {"speed", "Tool speed (cm/s)"},
        {"light", "Rate of brightness (%)"},
        {"distractors", "Distraction from similar objects"},
        {"occlusion", "Occlusion"},
        {"smoke", "Smoke"},
        {"blur", "Motion blur"},
        {"tools", "Number of tools"}};
    auto it = kTitles.find(factor);
    return it != kTitles.end() ? it->second : factor;
}

namespace {
double first_number(const std::string& s) {
    for (std::size_t i = 0; i < s.size(); ++i)
        if ((s[i] >= '0' && s[i] <= '9') || (s[i] == '.' && i + 1 < s.size()))
            return std::strtod(s.c_str() + i, nullptr);
    return 1e300;  // no number: after the numeric levels
}
}  // namespace

std::vector<LevelScore> ordered_levels(const std::vector<LevelScore>& levels) {
    // The book's factors first, in table 4.1's order; then the others by name.
    std::vector<std::string> factors = {"speed", "light", "distractors"};
    std::vector<std::string> others;
    for (const LevelScore& l : levels)
        if (std::find(factors.begin(), factors.end(), l.factor) == factors.end() &&
            std::find(others.begin(), others.end(), l.factor) == others.end())
            others.push_back(l.factor);
    std::sort(others.begin(), others.end());
    factors.insert(factors.end(), others.begin(), others.end());
    std::vector<LevelScore> out = levels;
    std::stable_sort(out.begin(), out.end(), [&](const LevelScore& a, const LevelScore& b) {
        const auto fa = std::find(factors.begin(), factors.end(), a.factor);
        const auto fb = std::find(factors.begin(), factors.end(), b.factor);
        if (fa != fb) return fa < fb;
        const double na = first_number(a.level), nb = first_number(b.level);
        if (na != nb) return na < nb;
        return a.level < b.level;
    });
    return out;
}

std::string pct(double fraction) { return fmt("%.1f", 100.0 * fraction); }

}  // namespace detail

std::vector<ThresholdCheck> check_thresholds(const EvalResult& r, const Thresholds& t) {
    std::vector<ThresholdCheck> out;
    auto add = [&](const std::optional<double>& limit, const char* name, bool at_least,
                   std::optional<double> value) {
        if (!limit) return;
        ThresholdCheck c{name, at_least ? ">=" : "<=", *limit, value, false};
        c.pass = value && (at_least ? *value >= *limit : *value <= *limit);
        out.push_back(c);
    };
    const ToolScore& s = r.tools;
    auto when = [](bool ok, double v) { return ok ? std::optional<double>(v) : std::nullopt; };
    add(t.min_success, "success rate", true, when(s.tool_frames > 0, s.success_rate));
    add(t.max_mean_error_px, "mean error (px)", false, when(s.matched > 0, s.mean_error_px));
    add(t.max_p95_error_px, "p95 error (px)", false, when(s.matched > 0, s.p95_error_px));
    add(t.max_mean_error_mm, "mean 3-D tip error (mm)", false, when(s.with_mm > 0, s.mean_error_mm));
    add(t.max_false_positives, "false positives per frame", false,
        when(s.frames > 0, s.false_positives_per_frame));
    add(t.min_identity, "identity consistency", true, s.identity_consistency);
    add(t.min_gesture_rate, "gesture recognition rate", true, r.gestures.overall_rate());
    const int regions = r.regions.good + r.regions.ok + r.regions.fail;
    add(t.min_region_good, "region GOOD fraction", true,
        when(r.regions.present && regions > 0, static_cast<double>(r.regions.good) / std::max(regions, 1)));
    add(t.max_corner_error_px, "mean corner error (px)", false,
        when(r.regions.with_corners > 0, r.regions.mean_corner_error_px));
    return out;
}

}  // namespace endotower::eval
