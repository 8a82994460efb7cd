// endotower scene: renders a scenario file into numbered PNG frames with exact ground
// truth (docs/scenario.md, docs/truth.md).
#include <cstdio>
#include <cstdlib>
#include <string>

#include "commands.hpp"
#include "endotower/scene/recording.hpp"

namespace endotower::firmware {

namespace {

void print_scene_help() {
    std::printf(
        "usage: endotower scene --scenario FILE --out DIR [--seed N] [--frames N]\n"
        "                       [--size 640x480|1920x1080] [--scale K] [--labels]\n\n"
        "Renders a synthetic laparoscopic recording with exact ground truth:\n"
        "DIR/frames/000000.png ... (input for 'endotower sim --input DIR/frames'),\n"
        "DIR/truth.jsonl (one line per frame, docs/truth.md) and DIR/scenario.yaml.\n"
        "Written into DIR.tmp-XXXXXX, then renamed to DIR. Deterministic: the same\n"
        "scenario and seed give the same bytes.\n\n"
        "  --scenario FILE  scenario, YAML (docs/scenario.md; suites in board/sim/scenarios)\n"
        "  --out DIR        output directory (replaces an earlier recording there)\n"
        "  --seed N         random seed (default: the scenario's seed)\n"
        "  --frames N       frame count (default: the scenario's frames)\n"
        "  --size WxH       640x480 or 1920x1080 (default: the scenario's size)\n"
        "  --scale K        multiply every duration given in frames by K (bigger suites)\n"
        "  --labels         also DIR/labels/000000.png ...: per pixel 0 none, 1.. tool index + 1,\n"
        "                   255 mixed by motion blur (training data for per-pixel models)\n\n"
        "Exit status: 0 done, 1 failed while writing, 2 bad usage or scenario (the\n"
        "message names the file, line and field).\n");
}

int usage_error(const std::string& m) {
    std::fprintf(stderr, "endotower scene: %s\n(see 'endotower scene --help')\n", m.c_str());
    return kExitBadInput;
}

bool parse_uint(const std::string& s, unsigned long long max, unsigned long long& out) {
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 19)
        return false;
    out = std::strtoull(s.c_str(), nullptr, 10);
    return out <= max;
}

}  // namespace

int run_scene_command(const Args& args) {
    scene::RecordingOptions o;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        if (k == "--help" || k == "-h") {
            print_scene_help();
            return kExitOk;
        }
        if (k == "--labels") {
            o.labels = true;
            continue;
        }
        if (k != "--scenario" && k != "--out" && k != "--seed" && k != "--frames" &&
            k != "--size" && k != "--scale")
            return usage_error("unknown option '" + k + "'");
        if (i + 1 >= args.size()) return usage_error("option " + k + " needs a value");
        const std::string& v = args[++i];
        unsigned long long n = 0;
        if (k == "--scenario") {
            o.scenario_path = v;
        } else if (k == "--out") {
            o.out_dir = v;
        } else if (k == "--seed") {
            if (!parse_uint(v, ~0ull, n))
                return usage_error("--seed needs a whole number >= 0, got '" + v + "'");
            o.seed = n;
        } else if (k == "--frames") {
            if (!parse_uint(v, 1000000, n) || n == 0)
                return usage_error("--frames needs a whole number in 1..1000000, got '" + v + "'");
            o.frames = static_cast<int>(n);
        } else if (k == "--size") {
            if (v == "640x480")
                o.width = 640, o.height = 480;
            else if (v == "1920x1080")
                o.width = 1920, o.height = 1080;
            else
                return usage_error("--size needs 640x480 or 1920x1080, got '" + v + "'");
        } else {
            char* end = nullptr;
            o.scale = std::strtod(v.c_str(), &end);
            if (v.empty() || *end != 0 || !(o.scale >= 0.01 && o.scale <= 1000))
                return usage_error("--scale needs a number in 0.01..1000, got '" + v + "'");
        }
    }
    if (o.scenario_path.empty()) return usage_error("give --scenario FILE");
    if (o.out_dir.empty()) return usage_error("give --out DIR");

    scene::RecordingStats stats;
    std::string error;
    switch (scene::write_recording(o, stats, error)) {
        case scene::RecordingResult::kOk:
            std::printf(
                "scene: %d frames -> %s (setup %.0f ms, render %.1f ms/frame, write %.1f "
                "ms/frame)\n",
                stats.frames, o.out_dir.c_str(), stats.setup_ms, stats.render_ms_per_frame,
                stats.write_ms_per_frame);
            return kExitOk;
        case scene::RecordingResult::kBadInput:
            std::fprintf(stderr, "endotower scene: %s\n", error.c_str());
            return kExitBadInput;
        case scene::RecordingResult::kFailed:
            break;
    }
    std::fprintf(stderr, "endotower scene: %s\n", error.c_str());
    return kExitFailure;
}

}  // namespace endotower::firmware
