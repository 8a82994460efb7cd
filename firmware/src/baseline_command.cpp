// endotower baseline: OpenCV's general-purpose trackers (CSRT, KCF) on a rendered
// scene, initialised from the ground truth, for the side-by-side comparison of
// docs/tracking.md. Writes a trace that `endotower eval` scores like any other.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/tracking.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "endotower/eval/truth.hpp"
#include "endotower/system/syscall.hpp"

namespace endotower::firmware {

namespace {

void print_help() {
    std::printf(
        "usage: endotower baseline --tracker csrt|kcf --scene DIR --trace FILE\n\n"
        "Runs OpenCV's CSRT or KCF tracker over a scene of 'endotower scene' (DIR/frames/*.png,\n"
        "DIR/truth.jsonl), initialised from the truth: a box over the first visible tool's\n"
        "tip and head, one shaft width of margin. Per frame the box's motion and scale carry\n"
        "the initial tip and head (the axis stays the initial one: boxes do not rotate);\n"
        "the trace (docs/trace.md members frame..stages_us.analysis and tools) is scored\n"
        "with 'endotower eval --trace FILE --truth DIR/truth.jsonl'. Re-initialises never:\n"
        "a lost box is 'no tool' to the end.\n\n"
        "Exit status: 0 done, 1 failed while running, 2 bad usage or input.\n");
}

int usage_error(const std::string& m) {
    std::fprintf(stderr, "endotower baseline: %s\n(see 'endotower baseline --help')\n", m.c_str());
    return kExitBadInput;
}

}  // namespace

int run_baseline_command(const Args& args) {
    std::string kind, scene, trace_path;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        if (k == "--help" || k == "-h") {
            print_help();
            return kExitOk;
        }
        if (i + 1 >= args.size()) return usage_error("option " + k + " needs a value");
        const std::string& v = args[++i];
        if (k == "--tracker")
            kind = v;
        else if (k == "--scene")
            scene = v;
        else if (k == "--trace")
            trace_path = v;
        else
            return usage_error("unknown option '" + k + "'");
    }
    if (kind != "csrt" && kind != "kcf")
        return usage_error("--tracker is csrt or kcf, got '" + kind + "'");
    if (scene.empty() || trace_path.empty())
        return usage_error("give --scene DIR and --trace FILE");

    std::vector<eval::TruthFrame> truth;
    std::string error;
    if (!eval::read_truth(scene + "/truth.jsonl", truth, error)) {
        std::fprintf(stderr, "endotower baseline: %s\n", error.c_str());
        return kExitBadInput;
    }
    std::vector<std::string> frames;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(scene + "/frames", ec))
        if (e.path().extension() == ".png") frames.push_back(e.path().string());
    if (ec || frames.empty()) return usage_error("no frames in " + scene + "/frames");
    std::sort(frames.begin(), frames.end());
    if (frames.size() != truth.size())
        return usage_error(scene + ": " + std::to_string(frames.size()) + " frames but " +
                           std::to_string(truth.size()) + " truth lines");

    cv::Ptr<cv::Tracker> tracker;
    bool started = false, lost = false;
    cv::Rect box0;
    eval::TruthTool tool0;
    std::string out;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const cv::Mat img = cv::imread(frames[i], cv::IMREAD_COLOR);
        if (img.empty()) {
            std::fprintf(stderr, "endotower baseline: cannot read %s\n", frames[i].c_str());
            return kExitBadInput;
        }
        nlohmann::json line = {
            {"frame", i},           {"seq", i},          {"capture_ns", 0},
            {"present_ns", 0},      {"latency_ns", 0},   {"late", false},
            {"passthrough", false}, {"analysis_age", 0}, {"tools", nlohmann::json::array()}};
        const auto t0 = std::chrono::steady_clock::now();
        cv::Rect box;
        bool have = false;
        if (!started && !truth[i].tools.empty() && truth[i].tools[0].visible) {
            tool0 = truth[i].tools[0];
            const double m = std::max(4.0, tool0.width_px);
            const cv::Rect2d b(std::min(tool0.tip_px.x, tool0.head_px.x) - m,
                               std::min(tool0.tip_px.y, tool0.head_px.y) - m,
                               std::abs(tool0.tip_px.x - tool0.head_px.x) + 2 * m,
                               std::abs(tool0.tip_px.y - tool0.head_px.y) + 2 * m);
            box0 = cv::Rect(b) & cv::Rect(0, 0, img.cols, img.rows);
            tracker = kind == "csrt" ? cv::Ptr<cv::Tracker>(cv::TrackerCSRT::create())
                                     : cv::Ptr<cv::Tracker>(cv::TrackerKCF::create());
            tracker->init(img, box0);
            started = have = true;
            box = box0;
        } else if (started && !lost) {
            have = tracker->update(img, box);
            lost = !have;
        }
        const auto us = std::chrono::duration_cast<std::chrono::microseconds>(
            std::chrono::steady_clock::now() - t0);
        line["stages_us"] = {{"analysis", us.count()}};
        if (have && box0.width > 0 && box0.height > 0) {
            // The initial tip and head, moved and scaled with the box.
            const double sx = static_cast<double>(box.width) / box0.width,
                         sy = static_cast<double>(box.height) / box0.height;
            auto carry = [&](eval::Point2 p) {
                return nlohmann::json::array(
                    {box.x + (p.x - box0.x) * sx, box.y + (p.y - box0.y) * sy});
            };
            line["tools"].push_back({{"id", 0},
                                     {"tip_px", carry(tool0.tip_px)},
                                     {"head_px", carry(tool0.head_px)},
                                     {"axis_deg", tool0.axis_deg},
                                     {"confidence", 1.0},
                                     {"tip_mm", nullptr}});
        }
        out += line.dump() + "\n";
    }
    if (!system::write_file_atomic(trace_path, out, error)) {
        std::fprintf(stderr, "endotower baseline: %s\n", error.c_str());
        return kExitFailure;
    }
    std::printf("baseline %s: %zu frames -> %s\n", kind.c_str(), frames.size(), trace_path.c_str());
    return kExitOk;
}

}  // namespace endotower::firmware
