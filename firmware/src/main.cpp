// endotower: the composition root. Reads the command and the board file, builds the
// drivers and hands them to the application.
#include <cstdio>
#include <string>
#include <vector>

#include "sim_command.hpp"

#ifndef ENDOTOWER_VERSION
#define ENDOTOWER_VERSION "0.0.0"
#endif

namespace {

void print_help() {
    std::printf(
        "usage: endotower COMMAND [OPTIONS]\n\n"
        "Inline endoscopy video appliance: live video at a fixed latency with tool\n"
        "tracking and overlays.\n\n"
        "commands:\n"
        "  sim        run on a recording, write the output video and a per-frame trace\n\n"
        "  --help     this text; 'endotower COMMAND --help' for a command\n"
        "  --version  print the version\n");
}

}  // namespace

int main(int argc, char** argv) {
    using namespace endotower::firmware;
    std::vector<std::string> args(argv + 1, argv + argc);
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
    if (cmd == "sim") return run_sim_command(args);
    std::fprintf(stderr, "endotower: unknown command '%s' (see 'endotower --help')\n", cmd.c_str());
    return kExitBadInput;
}
