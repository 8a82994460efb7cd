// Faults while writing files (issue 10, docs/reliability.md): the process killed with
// SIGKILL at random moments while it rewrites a file through write_file_atomic (the
// writer of calibrations, gesture and tool models, selftest and eval reports), and
// the disk filling up under it (RLIMIT_FSIZE: the unprivileged stand-in for a full
// tmpfs; the trace writer's ENOSPC case is TraceWriter.DiskFull... in tests/unit/app).
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <random>
#include <sstream>

#include "../sim/test_util.hpp"
#include "endotower/system/syscall.hpp"

namespace endotower::test {
namespace {

// Version k of the file: a header naming k, then a body whose length and bytes depend
// on k (8 KiB to 1 MiB, so a kill lands inside write() as well as between calls),
// then an end marker. Any mix of two versions or a cut-off one fails parse().
std::string version(int k) {
    const std::size_t body = 8192 + static_cast<std::size_t>(k % 16) * 65536;
    std::string s = "version " + std::to_string(k) + "\n";
    s.append(body, static_cast<char>('a' + k % 26));
    s += "\nend " + std::to_string(k) + "\n";
    return s;
}

// The version the file holds, or -1 when it is not exactly one complete version.
int parse(const std::string& text) {
    int k = -1;
    if (std::sscanf(text.c_str(), "version %d", &k) != 1 || k < 0) return -1;
    return text == version(k) ? k : -1;
}

std::string read_all(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::ostringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

TEST(FileFaults, SigkillMidWriteLeavesTheOldOrTheNewCompleteVersion) {
    sim::test::TempDir dir("sigkill");
    const std::string path = dir.file("calibration.json");
    std::string error;
    ASSERT_TRUE(system::write_file_atomic(path, version(0), error)) << error;
    std::mt19937 rng(20261123);  // fixed seed: the same kill moments every run
    int last = 0, advanced = 0;
    for (int round = 0; round < 40; ++round) {
        const pid_t child = ::fork();
        ASSERT_GE(child, 0);
        if (child == 0) {
            // Rewrite the file in a loop, from the version found there on.
            int k = parse(read_all(path));
            std::string err;
            for (;;)
                if (!system::write_file_atomic(path, version(++k), err)) ::_exit(3);
        }
        if (round % 4 == 3) {
            // Every fourth round first waits (up to 10 s) for a complete write, so that
            // kills land after one even where the writer is slow (TSan, a loaded CI).
            for (int i = 0; i < 10000 && parse(read_all(path)) <= last; ++i) ::usleep(1000);
        }
        ::usleep(std::uniform_int_distribution<unsigned>(200, 20000)(rng));
        ASSERT_EQ(::kill(child, SIGKILL), 0);
        int status = 0;
        ASSERT_EQ(::waitpid(child, &status, 0), child);
        ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
            << "the writer failed by itself: " << status;
        const int k = parse(read_all(path));
        ASSERT_GE(k, last) << "round " << round << ": the file is not one complete version";
        advanced += k > last;
        last = k;
    }
    EXPECT_GT(advanced, 0) << "no kill landed after a complete write: the writer never ran";
    // At most the one temporary file of the interrupted write is left beside it, and
    // the next write reuses it.
    for (const auto& name : dir.list())
        EXPECT_TRUE(name == "calibration.json" || name == "calibration.json.tmp") << name;
}

TEST(FileFaults, DiskFullMidWriteFailsWithTheErrnoAndKeepsTheOldFile) {
    sim::test::TempDir dir("fsize");
    const std::string path = dir.file("report.json");
    std::string error;
    ASSERT_TRUE(system::write_file_atomic(path, version(1), error)) << error;
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        // Files may not grow past 64 KiB in this process: write() fails with EFBIG
        // once the limit is reached, as it fails with ENOSPC on a full disk.
        std::signal(SIGXFSZ, SIG_IGN);
        const rlimit lim{65536, 65536};
        if (::setrlimit(RLIMIT_FSIZE, &lim) != 0) ::_exit(4);
        std::string err;
        const bool ok = system::write_file_atomic(path, version(15), err);  // ~1 MiB
        const bool named = err.find("write(" + path + ".tmp)") != std::string::npos &&
                           err.find("errno 27") != std::string::npos;
        ::_exit(ok ? 1 : named ? 0 : 2);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0)
        << "1: the write claimed success; 2: the error did not name the call, "
           "file and errno; 4: setrlimit failed";
    EXPECT_EQ(parse(read_all(path)), 1) << "the old version must be untouched";
    EXPECT_EQ(dir.list(), std::vector<std::string>{"report.json"})
        << "the partial temporary file must be removed";
}

}  // namespace
}  // namespace endotower::test
