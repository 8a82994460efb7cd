// `endotower scene` end to end, through the built binary.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

class SceneCommand : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("endotower_scene_cmd_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        std::ofstream(dir_ / "tiny.yaml")
            << "# tiny\nframes: 4\nseed: 9\ntools:\n"
               "  - {pivot_mm: [80, -50, 20], start: {tip_mm: [0, 0, 70]},\n"
               "     motion: [{move: [5, 5, 70], speed_cm_s: 3}]}\n";
    }
    void TearDown() override { fs::remove_all(dir_); }
    int run(const std::string& args) {
        const std::string cmd = std::string(ENDOTOWER_BINARY) + " " + args + " >" +
                                (dir_ / "out.txt").string() + " 2>" + (dir_ / "err.txt").string();
        const int st = std::system(cmd.c_str());
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }
    std::string err() const { return slurp(dir_ / "err.txt"); }
    fs::path dir_;
};

TEST_F(SceneCommand, WritesFramesTruthAndScenario) {
    const fs::path out = dir_ / "rec";
    ASSERT_EQ(run("scene --scenario " + (dir_ / "tiny.yaml").string() + " --out " + out.string()),
              0)
        << err();
    for (int i = 0; i < 4; ++i)
        EXPECT_TRUE(fs::is_regular_file(out / "frames" / ("00000" + std::to_string(i) + ".png")));
    EXPECT_FALSE(fs::exists(out / "frames" / "000004.png"));
    EXPECT_EQ(slurp(out / "scenario.yaml"), slurp(dir_ / "tiny.yaml"));
    std::istringstream lines(slurp(out / "truth.jsonl"));
    std::string line;
    int n = 0;
    while (std::getline(lines, line)) {
        const auto j = nlohmann::json::parse(line);
        EXPECT_EQ(j["frame"], n);
        EXPECT_EQ(j["t_ns"], n * 40000000LL);
        EXPECT_EQ(j["tools"].size(), 1u);
        EXPECT_EQ(j["camera"]["distortion"]["model"], "odd_radial");
        ++n;
    }
    EXPECT_EQ(n, 4);
    // No temporary directory is left beside it.
    for (const auto& e : fs::directory_iterator(dir_))
        EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos);

    // Options override the file; a second run replaces the first recording.
    ASSERT_EQ(run("scene --scenario " + (dir_ / "tiny.yaml").string() + " --out " + out.string() +
                  " --frames 2 --seed 4"),
              0)
        << err();
    EXPECT_FALSE(fs::exists(out / "frames" / "000002.png"));

    // And `endotower sim` replays it.
    const std::string sim = "sim --input " + (out / "frames").string() + " --out " +
                            (dir_ / "o.avi").string() + " --trace " +
                            (dir_ / "trace.jsonl").string() + " --events ''";
    ASSERT_EQ(run(sim), 0) << err();
    std::istringstream trace(slurp(dir_ / "trace.jsonl"));
    int frames = 0;
    while (std::getline(trace, line)) frames += line.find("\"frame\"") != std::string::npos ? 1 : 0;
    EXPECT_EQ(frames, 2);
}

TEST_F(SceneCommand, BadInputExitsTwoWithFileAndLine) {
    std::ofstream(dir_ / "bad.yaml")
        << "frames: 3\ntools:\n  - {diameter_mm: 8, start: {tip_mm: [0, 0, 60]}}\n";
    EXPECT_EQ(
        run("scene --scenario " + (dir_ / "bad.yaml").string() + " --out " + (dir_ / "x").string()),
        2);
    EXPECT_NE(err().find("bad.yaml:3: tools[0].diameter_mm: expected 5 or 10, got 8"),
              std::string::npos)
        << err();
    EXPECT_FALSE(fs::exists(dir_ / "x"));

    EXPECT_EQ(run("scene --scenario " + (dir_ / "missing.yaml").string() + " --out " +
                  (dir_ / "x").string()),
              2);
    EXPECT_NE(err().find("missing.yaml: cannot open"), std::string::npos) << err();
    EXPECT_EQ(run("scene --out " + (dir_ / "x").string()), 2);
    EXPECT_EQ(run("scene --scenario " + (dir_ / "tiny.yaml").string() + " --out " +
                  (dir_ / "x").string() + " --size 10x10"),
              2);
    EXPECT_NE(err().find("--size needs 640x480 or 1920x1080"), std::string::npos) << err();
    // An existing directory that is not a recording is not replaced.
    fs::create_directories(dir_ / "keep");
    std::ofstream(dir_ / "keep" / "notes.txt") << "mine";
    EXPECT_EQ(run("scene --scenario " + (dir_ / "tiny.yaml").string() + " --out " +
                  (dir_ / "keep").string()),
              2);
    EXPECT_EQ(slurp(dir_ / "keep" / "notes.txt"), "mine");
}

}  // namespace
