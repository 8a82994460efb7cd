// `endotower sim`: the appliance on a host, fed by a recording, shown into a file.
#pragma once

#include <string>
#include <vector>

namespace endotower::firmware {

// Exit codes shared by every command.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  // ran, but something failed while running
constexpr int kExitBadInput = 2; // usage, missing or malformed input

// argv after "sim". Prints the summary to stdout and errors to stderr.
int run_sim_command(const std::vector<std::string>& args);
void print_sim_help();

}  // namespace endotower::firmware
