// The per-process file a fuzz target writes its input to (the parsers under test read
// files): named by the process id, removed when libFuzzer ends the run with exit()
// (a crash leaves it, next to the crash input libFuzzer writes).
#pragma once

#include <unistd.h>

#include <cstdio>
#include <string>

namespace endotower::fuzz {

class ScratchFile {
public:
    explicit ScratchFile(const std::string& stem, const std::string& suffix = "")
        : path_("/tmp/" + stem + std::to_string(::getpid()) + suffix) {}
    ~ScratchFile() { std::remove(path_.c_str()); }
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;

    const std::string& path() const { return path_; }

private:
    std::string path_;
};

}  // namespace endotower::fuzz
