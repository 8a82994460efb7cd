// The endotower commands. Each lives in its own file (NAME_command.cpp) and takes the
// arguments after its name; it prints errors to stderr and returns an exit code.
#pragma once

#include <string>
#include <vector>

namespace endotower::firmware {

// Exit codes shared by every command.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;   // ran, but something failed while running
constexpr int kExitBadInput = 2;  // usage, missing or malformed input

using Args = std::vector<std::string>;

int run_sim_command(const Args& args);
int run_eval_command(const Args& args);
int run_scene_command(const Args& args);
int run_train_tool_model_command(const Args& args);
int run_calibrate_command(const Args& args);
int run_train_gestures_command(const Args& args);
int run_run_command(const Args& args);
int run_selftest_command(const Args& args);
int run_baseline_command(const Args& args);

}  // namespace endotower::firmware
