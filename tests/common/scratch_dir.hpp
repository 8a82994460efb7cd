// A per-process scratch directory for the tests that write files: temp dir /
// "endotower_NAME_PID", removed when the test program exits, so runs of the suite
// leave nothing in /tmp. Per process because CTest runs a file's tests in parallel.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

namespace endotower::test {

// `fresh`: empty it first (else files written earlier by this process stay).
inline std::filesystem::path scratch_dir(const std::string& name, bool fresh = true) {
    namespace fs = std::filesystem;
    struct Cleanup {
        std::mutex m;
        std::vector<fs::path> dirs;
        pid_t owner = ::getpid();
        ~Cleanup() {
            // A forked child that exits must not remove its parent's directories.
            if (::getpid() != owner) return;
            std::error_code ec;
            for (const fs::path& d : dirs) fs::remove_all(d, ec);
        }
    };
    static Cleanup cleanup;
    fs::path d =
        fs::temp_directory_path() / ("endotower_" + name + "_" + std::to_string(::getpid()));
    if (fresh) fs::remove_all(d);
    fs::create_directories(d);
    std::lock_guard<std::mutex> lock(cleanup.m);
    if (std::find(cleanup.dirs.begin(), cleanup.dirs.end(), d) == cleanup.dirs.end())
        cleanup.dirs.push_back(d);
    return d;
}

}  // namespace endotower::test
