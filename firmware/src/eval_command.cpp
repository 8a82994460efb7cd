// endotower eval: scores a trace against ground truth (the scene simulator's
// truth.jsonl or the sznitman_lap annotations) and writes a report. docs/evaluation.md.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <algorithm>
#include <optional>

#include "commands.hpp"
#include "endotower/eval/marker_metrics.hpp"
#include "endotower/eval/derived_truth.hpp"
#include "endotower/eval/report.hpp"
#include "endotower/system/syscall.hpp"

namespace endotower::firmware {

namespace {

namespace fs = std::filesystem;

void print_eval_help() {
    std::printf(
        "usage: endotower eval --trace FILE (--truth FILE | --sznitman XML [--first-index N] |\n"
        "                      --mask [FRAME:]PNG ... | --homography FILE [--homography-maps DIR]\n"
        "                      [--region POLYGON]) [--report DIR] [thresholds]\n\n"
        "Compares a trace of 'endotower sim' with ground truth: tool tracking success by the\n"
        "book's rule (tip within 2 x tool width, axis within 20 deg), tip errors, false\n"
        "positives, identity, per-factor rates; gesture confusion (table 3.3 layout);\n"
        "region GOOD/OK/FAIL and corner error. See docs/evaluation.md.\n\n"
        "  --trace FILE          the trace (JSON Lines, docs/trace.md)\n"
        "  --truth FILE          the simulator's truth.jsonl (docs/truth.md)\n"
        "  --sznitman XML        sznitman_lap annotations (train.xml); success when the head\n"
        "                        is within 0.5 x SCALE and the axis within 20 deg as lines\n"
        "  --first-index N       annotation index of trace frame 0 (default: the smallest)\n"
        "  --mask [FRAME:]PNG    a binary tool mask of trace frame FRAME (default 0), one\n"
        "                        instrument per component; repeat for more masks or frames.\n"
        "                        Tip = the component's end away from the image border, book rule\n"
        "  --homography FILE     H between the trace's first and last frame (FileStorage or\n"
        "                        9 numbers); the region marked at the first frame, mapped by H,\n"
        "                        is the truth at the last\n"
        "  --homography-maps D   first-to-last (default) or last-to-first (homography_pairs'\n"
        "                        *_model.txt map image B to A: last-to-first)\n"
        "  --region POLYGON      the marked region \"x1,y1 x2,y2 x3,y3 ...\" (first frame's px);\n"
        "                        default: the regions the trace reports at its first frame\n"
        "  --report DIR          write DIR/report.md and PNG plots (atomically)\n\n"
        "thresholds (exit status 1 when one fails; R is 0..1 or a percentage like 80%%):\n"
        "  --min-success R  --max-tip-error PX  --max-p95-tip-error PX  --max-tip-error-mm MM\n"
        "  --max-false-positives PER_FRAME  --min-identity R  --min-gesture-rate R\n"
        "  --min-region-good R  --max-corner-error PX\n"
        "  --max-marker-depth-error R  --max-marker-xy-error R (strip markers, mean relative\n"
        "                        errors of the marker position, tables 3.1/3.2; docs/markers.md)\n\n"
        "Exit status: 0 every threshold passed, 1 a threshold failed (or the report could\n"
        "not be written), 2 bad usage or malformed input (FILE:LINE: field message).\n");
}

int usage_error(const std::string& m) {
    std::fprintf(stderr, "endotower eval: %s\n(see 'endotower eval --help')\n", m.c_str());
    return kExitBadInput;
}

// A number; with `rate`, 0..1 or a percentage "80%".
bool parse_value(std::string s, bool rate, double& out) {
    bool percent = false;
    if (rate && !s.empty() && s.back() == '%') {
        percent = true;
        s.pop_back();
    }
    char* end = nullptr;
    out = std::strtod(s.c_str(), &end);
    if (s.empty() || end == nullptr || *end != 0 || !std::isfinite(out) || out < 0) return false;
    if (percent) out /= 100.0;
    return !rate || out <= 1.0;
}

// Writes the files into a fresh sibling directory, then renames it over DIR, so a
// reader never sees a half-written report (the old one is removed after the swap).
bool write_report(const std::string& dir, const std::vector<std::pair<std::string, std::string>>& files,
                  std::string& error) {
    const fs::path target = fs::absolute(dir).lexically_normal();
    std::string suffix = ".";
    suffix += std::to_string(::getpid());  // (not "." + ...: a GCC 12 -Wrestrict false positive)
    const fs::path tmp = target.string() + ".tmp" + suffix, old = target.string() + ".old" + suffix;
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    fs::remove_all(tmp, ec);
    if (!fs::create_directory(tmp, ec)) {
        error = "cannot create " + tmp.string() + ": " + ec.message();
        return false;
    }
    for (const auto& [name, data] : files)
        if (!system::write_file_atomic((tmp / name).string(), data, error)) {
            fs::remove_all(tmp, ec);
            return false;
        }
    const bool had_old = fs::exists(target);
    if (had_old) {
        fs::rename(target, old, ec);
        if (ec) {
            error = "cannot replace " + target.string() + ": " + ec.message();
            fs::remove_all(tmp, ec);
            return false;
        }
    }
    fs::rename(tmp, target, ec);
    if (ec) {
        error = "cannot rename " + tmp.string() + " to " + target.string() + ": " + ec.message();
        if (had_old) fs::rename(old, target, ec);
        fs::remove_all(tmp, ec);
        return false;
    }
    if (had_old) fs::remove_all(old, ec);
    return true;
}

}  // namespace

int run_eval_command(const Args& args) {
    std::string trace, truth, sznitman, report, homography, maps = "first-to-last", region;
    std::vector<std::pair<std::int64_t, std::string>> masks;
    std::optional<int> first_index;
    eval::Thresholds th;
    std::optional<double> max_marker_depth, max_marker_xy;
    struct Limit {
        const char* flag;
        std::optional<double> eval::Thresholds::*field;
        bool rate;
    };
    const Limit limits[] = {{"--min-success", &eval::Thresholds::min_success, true},
                            {"--max-tip-error", &eval::Thresholds::max_mean_error_px, false},
                            {"--max-p95-tip-error", &eval::Thresholds::max_p95_error_px, false},
                            {"--max-tip-error-mm", &eval::Thresholds::max_mean_error_mm, false},
                            {"--max-false-positives", &eval::Thresholds::max_false_positives, false},
                            {"--min-identity", &eval::Thresholds::min_identity, true},
                            {"--min-gesture-rate", &eval::Thresholds::min_gesture_rate, true},
                            {"--min-region-good", &eval::Thresholds::min_region_good, true},
                            {"--max-corner-error", &eval::Thresholds::max_corner_error_px, false}};
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        if (k == "--help" || k == "-h") {
            print_eval_help();
            return kExitOk;
        }
        if (i + 1 >= args.size()) return usage_error(k.rfind("--", 0) == 0 ? "option " + k + " needs a value" : "unexpected argument '" + k + "'");
        const std::string& v = args[++i];
        if (k == "--trace") trace = v;
        else if (k == "--truth") truth = v;
        else if (k == "--sznitman") sznitman = v;
        else if (k == "--report") report = v;
        else if (k == "--homography") homography = v;
        else if (k == "--homography-maps") maps = v;
        else if (k == "--region") region = v;
        else if (k == "--max-marker-depth-error" || k == "--max-marker-xy-error") {
            double x = 0;
            if (!parse_value(v, true, x)) return usage_error(k + " needs a rate in 0..1 (or 0..100%), got '" + v + "'");
            (k == "--max-marker-depth-error" ? max_marker_depth : max_marker_xy) = x;
        }
        else if (k == "--mask") {
            std::int64_t frame = 0;
            std::string file = v;
            const std::size_t colon = v.find(':');
            if (colon != std::string::npos && colon > 0 &&
                v.find_first_not_of("0123456789") == colon) {
                frame = std::strtoll(v.substr(0, colon).c_str(), nullptr, 10);
                file = v.substr(colon + 1);
            }
            masks.emplace_back(frame, file);
        }
        else if (k == "--first-index") {
            char* end = nullptr;
            const long n = std::strtol(v.c_str(), &end, 10);
            if (v.empty() || *end != 0 || n < 0 || n > 100000000)
                return usage_error("--first-index needs a frame number, got '" + v + "'");
            first_index = static_cast<int>(n);
        } else {
            const Limit* l = nullptr;
            for (const Limit& c : limits)
                if (k == c.flag) l = &c;
            if (l == nullptr) return usage_error("unknown option '" + k + "'");
            double x = 0;
            if (!parse_value(v, l->rate, x))
                return usage_error(k + (l->rate ? " needs a rate in 0..1 (or 0..100%)" : " needs a number >= 0") +
                                   ", got '" + v + "'");
            th.*(l->field) = x;
        }
    }
    if (trace.empty()) return usage_error("give the trace with --trace FILE");
    const int modes = !truth.empty() + !sznitman.empty() + !masks.empty() + !homography.empty();
    if (modes != 1)
        return usage_error("give exactly one kind of ground truth: --truth FILE, --sznitman XML, --mask PNG or "
                           "--homography FILE");
    if (first_index && sznitman.empty()) return usage_error("--first-index goes with --sznitman");
    if (maps != "first-to-last" && maps != "last-to-first")
        return usage_error("--homography-maps is first-to-last or last-to-first, got '" + maps + "'");
    if (!region.empty() && homography.empty()) return usage_error("--region goes with --homography");

    if ((max_marker_depth || max_marker_xy) && truth.empty())
        return usage_error("the marker thresholds go with --truth (the simulator's strip markers)");
    eval::EvalResult r;
    eval::MarkerScore markers;
    r.trace_path = trace;
    std::vector<eval::AnalysisFrame> frames;
    std::string error;
    if (!eval::read_analysis_trace(trace, frames, error)) {
        std::fprintf(stderr, "endotower eval: %s\n", error.c_str());
        return kExitBadInput;
    }
    for (const eval::AnalysisFrame& f : frames) r.has_tools = r.has_tools || f.has_tools;
    if (!truth.empty()) {
        std::vector<eval::TruthFrame> gt;
        if (!eval::read_truth(truth, gt, error)) {
            std::fprintf(stderr, "endotower eval: %s\n", error.c_str());
            return kExitBadInput;
        }
        r.truth_path = truth;
        r.tools = eval::score_tools(gt, frames);
        r.gestures = eval::score_gestures(gt, frames);
        r.regions = eval::score_regions(gt, frames);
        markers = eval::score_markers(gt, frames);
    } else if (!masks.empty()) {
        std::vector<eval::TruthFrame> gt;
        for (const auto& entry : masks) {
            const std::int64_t frame = entry.first;  // (a plain variable: lambdas may not capture bindings in clang 14)
            const std::string& file = entry.second;
            eval::ToolMask mask;
            if (!eval::read_tool_mask(file, mask, error)) {
                std::fprintf(stderr, "endotower eval: %s\n", error.c_str());
                return kExitBadInput;
            }
            auto it = std::find_if(gt.begin(), gt.end(), [&](const eval::TruthFrame& f) { return f.frame == frame; });
            if (it == gt.end()) {
                gt.emplace_back();
                gt.back().frame = frame;
                it = gt.end() - 1;
            }
            for (eval::TruthTool t : eval::tools_from_mask(mask)) {
                t.id = static_cast<int>(it->tools.size()) + 1;
                it->tools.push_back(t);
            }
        }
        std::sort(gt.begin(), gt.end(), [](const eval::TruthFrame& a, const eval::TruthFrame& b) { return a.frame < b.frame; });
        // Only the masked frames are scored.
        std::vector<eval::AnalysisFrame> masked;
        for (const eval::AnalysisFrame& f : frames)
            for (const eval::TruthFrame& g : gt)
                if (g.frame == f.frame) masked.push_back(f);
        r.truth_path = masks.front().second + (masks.size() > 1 ? " (+" + std::to_string(masks.size() - 1) + " masks)" : "");
        r.tools = eval::score_tools(gt, masked);
    } else if (!homography.empty()) {
        eval::Homography h;
        if (!eval::read_homography(homography, h, error)) {
            std::fprintf(stderr, "endotower eval: %s\n", error.c_str());
            return kExitBadInput;
        }
        if (maps == "last-to-first") {
            eval::Homography inv;
            eval::invert_homography(h, inv);
            h = inv;
        }
        if (frames.empty()) {
            std::fprintf(stderr, "endotower eval: %s: the trace has no frames\n", trace.c_str());
            return kExitBadInput;
        }
        std::vector<std::vector<eval::Point2>> polys;
        std::int64_t first = frames.front().frame;
        if (!region.empty()) {
            polys.emplace_back();
            if (!eval::parse_polygon(region, polys.back(), error)) return usage_error("--region: " + error);
        } else {
            polys = eval::first_trace_polygons(frames, first);
            if (polys.empty()) {
                std::fprintf(stderr, "endotower eval: %s: no frame has a 'regions' member; mark the region "
                             "with --region\n", trace.c_str());
                return kExitBadInput;
            }
        }
        std::vector<eval::TruthFrame> gt;
        if (!eval::region_truth_from_homography(polys, h, first, frames.back().frame, gt, error)) {
            std::fprintf(stderr, "endotower eval: %s: %s\n", homography.c_str(), error.c_str());
            return kExitBadInput;
        }
        // Polygons read from the trace's first frame match it by construction: score the last only.
        if (region.empty() && gt.size() == 2) gt.erase(gt.begin());
        r.truth_path = homography;
        r.regions = eval::score_regions(gt, frames);
    } else {
        eval::SznitmanAnnotations ann;
        if (!eval::read_sznitman(sznitman, ann, error)) {
            std::fprintf(stderr, "endotower eval: %s\n", error.c_str());
            return kExitBadInput;
        }
        int first = first_index.value_or(0);
        if (!first_index && !ann.frames.empty()) {
            first = ann.frames.front().index;
            for (const eval::SznitmanFrame& f : ann.frames) first = std::min(first, f.index);
        }
        r.sznitman = true;
        r.truth_path = sznitman;
        r.tools = eval::score_sznitman(ann, frames, first);
    }
    const std::vector<eval::ThresholdCheck> checks = eval::check_thresholds(r, th);
    std::fputs(eval::render_summary(r, checks).c_str(), stdout);
    if (!report.empty()) {
        std::vector<std::pair<std::string, std::string>> files = eval::render_plots(r);
        files.emplace_back("report.md", eval::render_markdown(r, checks));
        if (!write_report(report, files, error)) {
            std::fprintf(stderr, "endotower eval: cannot write the report: %s\n", error.c_str());
            return kExitFailure;
        }
        std::printf("report: %s/report.md\n", report.c_str());
    }
    // Strip markers (issue 6): scored when the truth has them.
    bool markers_pass = true;
    if (!markers.empty()) std::fputs(eval::render_marker_summary(markers).c_str(), stdout);
    const auto marker_check = [&](const char* what, const std::optional<double>& limit, std::optional<double> value) {
        if (!limit) return;
        const bool pass = value && *value <= *limit;
        if (value)
            std::printf("threshold %s: %.2f %% <= %.2f %%: %s\n", what, 100 * *value, 100 * *limit, pass ? "pass" : "FAIL");
        else
            std::printf("threshold %s: no located marker: FAIL\n", what);
        markers_pass = markers_pass && pass;
    };
    marker_check("marker depth error", max_marker_depth,
                 markers.depth_n > 0 ? std::optional<double>(markers.depth_error) : std::nullopt);
    marker_check("marker x error", max_marker_xy,
                 markers.x_n > 0 ? std::optional<double>(markers.x_error) : std::nullopt);
    marker_check("marker y error", max_marker_xy,
                 markers.y_n > 0 ? std::optional<double>(markers.y_error) : std::nullopt);
    for (const eval::ThresholdCheck& c : checks)
        if (!c.pass) return kExitFailure;
    return markers_pass ? kExitOk : kExitFailure;
}

}  // namespace endotower::firmware
