// Runs the built `endotower` (ENDOTOWER_BINARY, set by endotower_gtest) with a
// command line, for the tests that exercise the executable end to end.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace endotower::test {

struct CommandRun {
    int status = -1;     // exit status; -1 when it could not run or did not exit
    std::string output;  // stdout and stderr together
};

// `args` is appended to the binary as given (the shell splits and quotes it).
inline CommandRun run_endotower(const std::string& args) {
    const std::string cmd = std::string(ENDOTOWER_BINARY) + " " + args + " 2>&1";
    CommandRun r;
    FILE* p = ::popen(cmd.c_str(), "r");
    if (p == nullptr) return r;
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), buf.size(), p) != nullptr) r.output += buf.data();
    const int st = ::pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

}  // namespace endotower::test
