// The book's trackers end to end (issue 5): selected by name in a board file for
// `endotower sim`, and `endotower baseline` (OpenCV's CSRT/KCF from the truth's box)
// producing a trace that `endotower eval` scores.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "endotower_command.hpp"

namespace fs = std::filesystem;
using endotower::test::run_endotower;

namespace {

class TrackersCli : public ::testing::Test {
protected:
    static fs::path dir() {
        return fs::temp_directory_path() / ("endotower_trackers_" + std::to_string(::getpid()));
    }
    static void SetUpTestSuite() {
        fs::create_directories(dir());
        // A still grasper, 8 frames: a box tracker must keep the truth's tip exactly.
        std::ofstream(dir() / "still.yaml")
            << "name: still\nframes: 8\nseed: 3\nlight: 0.8\ntools:\n"
               "  - {diameter_mm: 5, tip: grasper, jaw: closed, pivot_mm: [85, -55, 15], "
               "start: {tip_mm: [0, 4, 72]}}\n";
        const auto r = run_endotower("scene --scenario " + (dir() / "still.yaml").string() +
                                     " --out " + (dir() / "scene").string());
        ASSERT_EQ(r.status, 0) << r.output;
    }
    static void TearDownTestSuite() { fs::remove_all(dir()); }
};

TEST_F(TrackersCli, BaselineKeepsAStillToolsTipAndEvalScoresIt) {
    const std::string trace = (dir() / "kcf.jsonl").string();
    auto r = run_endotower("baseline --tracker kcf --scene " + (dir() / "scene").string() +
                           " --trace " + trace);
    ASSERT_EQ(r.status, 0) << r.output;
    std::ifstream t(trace), truth(dir() / "scene" / "truth.jsonl");
    std::string a, b;
    int lines = 0;
    while (std::getline(t, a) && std::getline(truth, b)) {
        const auto ja = nlohmann::json::parse(a), jb = nlohmann::json::parse(b);
        ASSERT_EQ(ja["tools"].size(), 1u) << a;
        const auto& tip = ja["tools"][0]["tip_px"];
        const auto& truth_tip = jb["tools"][0]["tip_px"];
        EXPECT_NEAR(tip[0].get<double>(), truth_tip[0].get<double>(), 2.0) << "frame " << lines;
        EXPECT_NEAR(tip[1].get<double>(), truth_tip[1].get<double>(), 2.0) << "frame " << lines;
        ++lines;
    }
    EXPECT_EQ(lines, 8);
    r = run_endotower("eval --trace " + trace + " --truth " +
                      (dir() / "scene" / "truth.jsonl").string() + " --min-success 100%");
    EXPECT_EQ(r.status, 0) << r.output;
}

TEST_F(TrackersCli, BaselineRefusesBadUsage) {
    auto r = run_endotower("baseline --tracker boosting --scene x --trace y");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("--tracker is csrt or kcf, got 'boosting'"), std::string::npos)
        << r.output;
    r = run_endotower("baseline --tracker csrt --scene /nonexistent --trace " +
                      (dir() / "x.jsonl").string());
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("/nonexistent/truth.jsonl"), std::string::npos) << r.output;
}

TEST_F(TrackersCli, SimRunsEveryBookTrackerByName) {
    for (const char* name : {"ekf", "mog2", "particle", "particle_sorted", "hybrid", "mhi"}) {
        const fs::path board = dir() / (std::string(name) + ".yaml");
        std::ofstream(board) << "board: t\nanalysis: {stage: none, tracker: " << name << "}\n";
        const std::string trace = (dir() / (std::string(name) + ".jsonl")).string();
        const auto r = run_endotower("sim --board " + board.string() + " --input " +
                                     (dir() / "scene" / "frames").string() + " --trace " + trace +
                                     " --out " + (dir() / "o.mp4").string() + " --events ''");
        ASSERT_EQ(r.status, 0) << name << ": " << r.output;
        std::ifstream t(trace);
        std::string line;
        int n = 0;
        while (std::getline(t, line)) n += nlohmann::json::parse(line).contains("tools");
        EXPECT_EQ(n, 8) << name << ": every frame's line carries its tools";
    }
}

}  // namespace
