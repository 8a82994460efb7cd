// endotower: the composition root. Reads the command and the board file, builds the
// drivers and hands them to the application.
#include <cstdio>
#include <string>
#include <vector>

#include "commands.hpp"

#ifndef ENDOTOWER_VERSION
#define ENDOTOWER_VERSION "0.0.0"
#endif

namespace {

using namespace endotower::firmware;

struct Command {
    const char* name;
    int (*run)(const Args&);
    const char* summary;
};

// One line per command, in the order `--help` lists them.
constexpr Command kCommands[] = {
    {"sim", run_sim_command, "run on a recording, write the output video and a per-frame trace"},
    {"eval", run_eval_command, "score a trace against ground truth, write a report"},
    {"scene", run_scene_command, "render a scenario: frames with exact ground truth"},
    {"train-tool-model", run_train_tool_model_command, "train the per-pixel tool likelihood of the likelihood tracker"},
    {"calibrate", run_calibrate_command, "calibrate the scope (centre, focal length, distortion), write its file"},
    {"train-gestures", run_train_gestures_command, "train the tool-gesture classifier from labelled recordings"},
    {"run", run_run_command, "the appliance: capture device to monitor, from the board file"},
    {"selftest", run_selftest_command, "check camera, handle, display, latency, files; write a report"},
    {"baseline", run_baseline_command, "OpenCV's CSRT/KCF on a scene from the truth's box, for comparison"},
};

void print_help() {
    std::printf(
        "usage: endotower COMMAND [OPTIONS]\n\n"
        "Inline endoscopy video appliance: live video at a fixed latency with tool\n"
        "tracking and overlays.\n\ncommands:\n");
    for (const Command& c : kCommands) std::printf("  %-14s %s\n", c.name, c.summary);
    std::printf(
        "\n  --help         this text; 'endotower COMMAND --help' for a command\n"
        "  --version      print the version\n");
}

}  // namespace

int main(int argc, char** argv) {
    Args args(argv + 1, argv + argc);
    if (args.empty()) {
        print_help();
        return kExitBadInput;
    }
    const std::string cmd = args.front();
    args.erase(args.begin());
    if (cmd == "--help" || cmd == "-h" || cmd == "help") {
        print_help();
        return kExitOk;
    }
    if (cmd == "--version") {
        std::printf("endotower %s\n", ENDOTOWER_VERSION);
        return kExitOk;
    }
    for (const Command& c : kCommands)
        if (cmd == c.name) return c.run(args);
    std::fprintf(stderr, "endotower: unknown command '%s' (see 'endotower --help')\n", cmd.c_str());
    return kExitBadInput;
}
