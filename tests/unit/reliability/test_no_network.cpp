// No network listener of any kind (issue 10): a replay of the shipped sim board under
// strace, recording every socket call of the process and its threads. The appliance
// may open AF_UNIX/AF_NETLINK sockets (udev and libusb hotplug; the service allows
// only those, endotower.service) but never an IP or packet socket, and never binds,
// listens or accepts. Skips when strace is absent or ptrace is not permitted.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "endotower_command.hpp"

namespace endotower::test {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

TEST(NoNetwork, ReplayOpensNoIpSocketAndListensOnNothing) {
    if (std::system("strace -o /dev/null true >/dev/null 2>&1") != 0)
        GTEST_SKIP() << "strace is absent or ptrace is not permitted here (apt-get install strace)";
    const fs::path dir =
        fs::temp_directory_path() / ("endotower_no_network_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path log = dir / "strace.txt";
    // The first 30 frames of the bundled recording: the sockets are opened at start-up
    // (udev, libusb hotplug), not per frame, and under the sanitizers the whole clip
    // would take minutes.
    {
        cv::VideoCapture clip(ENDOTOWER_SOURCE_DIR "/board/sim/media/endotip_rotation.mp4");
        ASSERT_TRUE(clip.isOpened());
        fs::create_directories(dir / "in");
        cv::Mat frame;
        for (int i = 0; i < 30; ++i) {
            ASSERT_TRUE(clip.read(frame)) << "frame " << i;
            char name[16];
            std::snprintf(name, sizeof name, "%03d.png", i);
            ASSERT_TRUE(cv::imwrite((dir / "in" / name).string(), frame));
        }
    }
    const std::string cmd =
        "strace -f -qq -e trace=socket,socketpair,bind,listen,accept,accept4,connect -o " +
        log.string() + " " + ENDOTOWER_BINARY +
        " sim --board " ENDOTOWER_SOURCE_DIR "/board/sim/board.yaml --input " +
        (dir / "in").string() + " --out " + (dir / "out.mkv").string() + " --trace " +
        (dir / "trace.jsonl").string() + " >" + (dir / "stdout.txt").string() + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::ifstream in(log);
    std::string line;
    int socket_calls = 0;
    while (std::getline(in, line)) {
        if (line.find("socket(") != std::string::npos ||
            line.find("socketpair(") != std::string::npos) {
            ++socket_calls;
            EXPECT_TRUE(line.find("AF_UNIX") != std::string::npos ||
                        line.find("AF_NETLINK") != std::string::npos)
                << "a socket of another family: " << line;
        }
        for (const char* call : {" bind(", " listen(", " accept(", " accept4("})
            EXPECT_EQ(line.find(call), std::string::npos) << line;
        if (line.find(" connect(") != std::string::npos) {
            EXPECT_NE(line.find("AF_UNIX"), std::string::npos)
                << "connect to something not local: " << line;
        }
    }
    EXPECT_TRUE(fs::exists(dir / "trace.jsonl")) << "the replay did not run to the end";
    EXPECT_NE(slurp(dir / "stdout.txt").find("30 frames in, 30 out"), std::string::npos)
        << slurp(dir / "stdout.txt");
    RecordProperty("socket_calls", socket_calls);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace endotower::test
