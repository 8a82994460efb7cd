// Board file parsing: values, defaults, path resolution, and errors naming the line
// and field.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "board_config.hpp"

namespace endotower::firmware {
namespace {

namespace fs = std::filesystem;

std::string write_board(const std::string& name, const std::string& text) {
    const fs::path dir = fs::temp_directory_path() / "endotower_board_test";
    fs::create_directories(dir);
    const fs::path p = dir / name;
    std::ofstream(p) << text;
    return p.string();
}

TEST(Board, TheShippedSimBoardLoads) {
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(ENDOTOWER_SOURCE_DIR "/board/sim/board.yaml", b, err)) << err;
    EXPECT_EQ(b.name, "sim");
    EXPECT_EQ(b.stage, "status_badge");
    EXPECT_TRUE(fs::exists(b.sim_input)) << b.sim_input;
    EXPECT_TRUE(fs::exists(b.sim_events)) << b.sim_events;
    EXPECT_FALSE(b.sim_realtime);
    EXPECT_TRUE(b.gestures);
    EXPECT_TRUE(fs::exists(b.gesture_model)) << b.gesture_model;
    EXPECT_DOUBLE_EQ(b.gesture_hold_ms, 1000.0);
}

TEST(Board, ValuesAndRelativePaths) {
    const std::string p = write_board("ok.yaml",
                                      "board: t\n"
                                      "video: {latency_ms: 20.5, compose_budget_ms: 3}\n"
                                      "analysis: {stage: none, max_overlay_age: 5}\n"
                                      "sim: {input: clip.mp4, output: /tmp/x.mkv, realtime: yes}\n");
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(p, b, err)) << err;
    EXPECT_DOUBLE_EQ(b.latency_ms, 20.5);
    EXPECT_DOUBLE_EQ(b.compose_budget_ms, 3);
    EXPECT_EQ(b.stage, "none");
    EXPECT_EQ(b.max_overlay_age, 5);
    EXPECT_EQ(b.sim_input, (fs::path(p).parent_path() / "clip.mp4").string());
    EXPECT_EQ(b.sim_output, "/tmp/x.mkv");
    EXPECT_TRUE(b.sim_realtime);
}

struct BadCase {
    const char* text;
    const char* message;  // after "FILE:"
};

TEST(Board, ErrorsNameTheLineAndField) {
    const BadCase cases[] = {
        {"board: t\nvideo:\n  latency_ms: fast\n",
         "3: field 'video.latency_ms': expected a number, got 'fast'"},
        {"board: t\nvideo:\n  latency_ms: -1\n", "3: field 'video.latency_ms': must be between 0 and 1000, got -1"},
        {"board: t\nvideo:\n  latncy_ms: 3\n",
         "3: field 'video.latncy_ms': unknown key (expected one of: latency_ms, compose_budget_ms, late_tolerance_ms)"},
        {"board: t\nanalysis:\n  stage: magic\n",
         "3: field 'analysis.stage': unknown stage 'magic' (expected status_badge or none)"},
        {"board: t\nanalysis:\n  tracker: cnn\n",
         "3: field 'analysis.tracker': unknown tracker 'cnn' (expected none, kalman, kalman_red or likelihood)"},
        {"board: t\nsim:\n  realtime: maybe\n", "3: field 'sim.realtime': expected true or false, got 'maybe'"},
        {"board: t\nanalysis:\n  max_overlay_age: 2.5\n", "3: field 'analysis.max_overlay_age': expected an integer"},
        {"video: {latency_ms: 1}\n", "1: field 'board': missing (the board's name)"},
        {"board: t\nvideo: [1, 2\n", "3: not valid YAML: end of sequence flow not found"},
        {"board: t\n? [a, b]\n: c\n", "2: field '(top level)': a key must be a plain name"},
        {"board: t\nsim:\n  ? {x: 1}\n  : y\n", "3: field 'sim': a key must be a plain name"},
        {"board: t\nanalysis:\n  gestures: {model: g.yml, hold: 3}\n",
         "3: field 'analysis.gestures.hold': unknown key (expected one of: model, hold_ms)"},
        {"board: t\nanalysis:\n  gestures:\n    hold_ms: 500\n",
         "4: field 'analysis.gestures.model': missing (a file of 'endotower train-gestures')"},
        {"board: t\nanalysis:\n  gestures:\n    model: g.yml\n    hold_ms: -5\n",
         "5: field 'analysis.gestures.hold_ms': must be between 0 and 60000, got -5"},
        {"board: t\nanalysis:\n  gestures: on\n",
         "3: field 'analysis.gestures': expected a map {model: FILE, hold_ms: N}"},
    };
    for (const auto& c : cases) {
        const std::string p = write_board("bad.yaml", c.text);
        BoardConfig b;
        std::string err;
        EXPECT_FALSE(load_board(p, b, err)) << c.text;
        EXPECT_EQ(err, p + ":" + c.message) << c.text;
    }
}

// Inputs the fuzzer (tests/fuzz) once crashed on: each must now load or be refused
// with a message naming the file.
TEST(Board, FuzzRegressionsAreRefusedCleanly) {
    const fs::path dir = fs::path(ENDOTOWER_SOURCE_DIR) / "tests/fuzz/regressions/board";
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        BoardConfig b;
        std::string err;
        if (!load_board(e.path().string(), b, err)) EXPECT_EQ(err.rfind(e.path().string(), 0), 0u) << err;
        ++n;
    }
    EXPECT_GE(n, 1);
}

TEST(Board, MissingAndEmptyFiles) {
    BoardConfig b;
    std::string err;
    EXPECT_FALSE(load_board("/nonexistent/board.yaml", b, err));
    EXPECT_EQ(err, "board file not found or unreadable: /nonexistent/board.yaml");
    const std::string p = write_board("empty.yaml", "");
    EXPECT_FALSE(load_board(p, b, err));
    EXPECT_EQ(err, p + ": board file is empty");
}

}  // namespace
}  // namespace endotower::firmware
