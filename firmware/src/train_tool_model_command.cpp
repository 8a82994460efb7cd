// endotower train-tool-model: trains the per-pixel tool likelihood (ToolLikelihood)
// from simulator recordings with labels and from real images with tool masks.
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <filesystem>

#include "commands.hpp"
#include "endotower/system/syscall.hpp"
#include "endotower/vision/tool_likelihood.hpp"

namespace endotower::firmware {

namespace {

namespace fs = std::filesystem;

void print_help() {
    std::printf(
        "usage: endotower train-tool-model (--scene DIR | --image IMG --mask PNG)... [--every N]\n"
        "                                  [--real-weight W] --out FILE\n\n"
        "Trains the per-pixel tool likelihood of the 'likelihood' tracker (docs/tracking.md)\n"
        "and writes the model file atomically.\n\n"
        "  --scene DIR       a recording of 'endotower scene --labels' (DIR/frames, DIR/labels)\n"
        "  --image IMG       a real frame, with\n"
        "  --mask PNG        its tool mask (nonzero = tool), same size\n"
        "  --every N         use every N-th frame of each scene (default 5)\n"
        "  --augment K       K extra copies of each image with random white balance (channel\n"
        "                    gains 1 +- S; default 4): real cameras tint the greys of tools\n"
        "  --gain-spread S   the white-balance spread S (default 0.05: larger spreads\n"
        "                    cost accuracy on the simulator suites, docs/tracking.md)\n"
        "  --real-weight W   a real pixel counts W simulated ones (default: so that the real\n"
        "                    images together weigh as much as the scenes together)\n"
        "  --out FILE        the model file (e.g. board/sim/models/tool_likelihood.bin)\n\n"
        "Exit status: 0 written, 1 could not write, 2 bad usage or input.\n");
}

int usage_error(const std::string& m) {
    std::fprintf(stderr, "endotower train-tool-model: %s\n(see 'endotower train-tool-model --help')\n", m.c_str());
    return kExitBadInput;
}

}  // namespace

int run_train_tool_model_command(const Args& args) {
    std::vector<std::string> scenes;
    std::vector<std::pair<std::string, std::string>> real;
    std::string out, pending_image;
    long every = 5, augment = 4;
    double spread = 0.05;
    double real_weight = -1;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        if (k == "--help" || k == "-h") {
            print_help();
            return kExitOk;
        }
        if (i + 1 >= args.size()) return usage_error("option " + k + " needs a value");
        const std::string& v = args[++i];
        char* end = nullptr;
        if (k == "--scene") scenes.push_back(v);
        else if (k == "--image") {
            if (!pending_image.empty()) return usage_error("--image " + pending_image + " has no --mask");
            pending_image = v;
        } else if (k == "--mask") {
            if (pending_image.empty()) return usage_error("--mask " + v + " must follow an --image");
            real.emplace_back(pending_image, v);
            pending_image.clear();
        } else if (k == "--every") {
            every = std::strtol(v.c_str(), &end, 10);
            if (v.empty() || *end != 0 || every < 1 || every > 100000) return usage_error("--every needs a whole number >= 1, got '" + v + "'");
        } else if (k == "--augment") {
            augment = std::strtol(v.c_str(), &end, 10);
            if (v.empty() || *end != 0 || augment < 0 || augment > 100) return usage_error("--augment needs a whole number in 0..100, got '" + v + "'");
        } else if (k == "--gain-spread") {
            spread = std::strtod(v.c_str(), &end);
            if (v.empty() || *end != 0 || !(spread >= 0 && spread < 0.9)) return usage_error("--gain-spread needs a number in 0..0.9, got '" + v + "'");
        } else if (k == "--real-weight") {
            real_weight = std::strtod(v.c_str(), &end);
            if (v.empty() || *end != 0 || !(real_weight > 0)) return usage_error("--real-weight needs a number > 0, got '" + v + "'");
        } else if (k == "--out") out = v;
        else return usage_error("unknown option '" + k + "'");
    }
    if (!pending_image.empty()) return usage_error("--image " + pending_image + " has no --mask");
    if (out.empty()) return usage_error("give --out FILE");
    if (scenes.empty() && real.empty()) return usage_error("give at least one --scene DIR or --image IMG --mask PNG");

    // Which scene frames to use, and the pixel counts that set the real images' weight.
    std::vector<std::pair<std::string, std::string>> sim;
    for (const std::string& d : scenes) {
        const fs::path frames = fs::path(d) / "frames", labels = fs::path(d) / "labels";
        if (!fs::is_directory(frames) || !fs::is_directory(labels))
            return usage_error(d + ": not a recording with labels (render it with 'endotower scene --labels')");
        std::vector<fs::path> names;
        for (const auto& e : fs::directory_iterator(labels)) names.push_back(e.path().filename());
        std::sort(names.begin(), names.end());
        if (names.empty()) return usage_error(labels.string() + ": no label images");
        for (std::size_t j = 0; j < names.size(); j += static_cast<std::size_t>(every))
            sim.emplace_back((frames / names[j]).string(), (labels / names[j]).string());
    }
    vision::ToolLikelihood model;
    std::string error;
    std::uint64_t seed = 1;
    for (const auto& [img, lab] : sim)
        if (!model.add_files(img, lab, 1.0, error, static_cast<int>(augment), spread, seed++)) {
            std::fprintf(stderr, "endotower train-tool-model: %s\n", error.c_str());
            return kExitBadInput;
        }
    if (real_weight < 0) real_weight = real.empty() ? 1.0 : std::max<double>(1.0, static_cast<double>(sim.size()) / real.size());
    for (const auto& [img, lab] : real)
        if (!model.add_files(img, lab, real_weight, error, static_cast<int>(augment), spread, seed++)) {
            std::fprintf(stderr, "endotower train-tool-model: %s\n", error.c_str());
            return kExitBadInput;
        }
    if (!model.finish(error)) {
        std::fprintf(stderr, "endotower train-tool-model: %s\n", error.c_str());
        return kExitBadInput;
    }
    if (!system::write_file_atomic(out, model.serialise(), error)) {
        std::fprintf(stderr, "endotower train-tool-model: %s\n", error.c_str());
        return kExitFailure;
    }
    std::printf("train-tool-model: %zu simulated frames, %zu real images (weight %.1f) -> %s\n", sim.size(),
                real.size(), real_weight, out.c_str());
    return kExitOk;
}

}  // namespace endotower::firmware
