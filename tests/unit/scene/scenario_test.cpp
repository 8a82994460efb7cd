#include "endotower/scene/scenario.hpp"

#include <gtest/gtest.h>

namespace endotower::scene {
namespace {

std::string error_of(const std::string& text) {
    Scenario s;
    std::string error;
    EXPECT_FALSE(parse_scenario(text, "bad.yaml", s, error));
    return error;
}

TEST(SceneScenario, ErrorsNameTheFileLineAndField) {
    EXPECT_EQ(error_of("frames: 10\ntols: []\n"), "bad.yaml:2: tols: unknown field");
    EXPECT_EQ(error_of("name: x\n"), "bad.yaml:1: frames: missing");
    EXPECT_EQ(error_of("frames: 0\n"), "bad.yaml:1: frames: must be in 1..1000000, got 0");
    EXPECT_EQ(error_of("frames: ten\n"), "bad.yaml:1: frames: expected a number, got 'ten'");
    EXPECT_EQ(error_of("frames: 10\nsize: 800x600\n"),
              "bad.yaml:2: size: expected 640x480 or 1920x1080, got '800x600'");
    EXPECT_EQ(error_of("frames: 10\ntools:\n  - start: {tip_mm: [0, 0, 60]}\n    diameter_mm: 7\n"),
              "bad.yaml:4: tools[0].diameter_mm: expected 5 or 10, got 7");
    EXPECT_EQ(error_of("frames: 10\ntools:\n  - start: {tip_mm: [0, 0, 60]}\n    tip: hook\n"),
              "bad.yaml:4: tools[0].tip: expected one of grasper, scissors, got 'hook'");
    EXPECT_EQ(error_of("frames: 10\ntools:\n  - start: {tip_mm: [0, 0]}\n"),
              "bad.yaml:3: tools[0].start.tip_mm: expected a list of 3 numbers");
    EXPECT_EQ(error_of("frames: 10\ntools:\n  - start: {tip_mm: [0, 0, 60]}\n    motion:\n"
                       "      - {move: [1, 2, 3]}\n"),
              "bad.yaml:5: tools[0].motion[0]: a move needs speed_cm_s or frames");
    EXPECT_EQ(
        error_of("frames: 10\ntools:\n  - start: {tip_mm: [0, 0, 60]}\n    motion:\n"
                 "      - {dwell: 3, loop: {}}\n"),
        "bad.yaml:5: tools[0].motion[0]: expected exactly one of move, pose, dwell, loop, wander");
    EXPECT_EQ(error_of("frames: 10\nlight: 1.5\n"), "bad.yaml:2: light: must be in 0..1, got 1.5");
    EXPECT_EQ(error_of("frames: 10\ndeformation: {radius_mm: 5, push_mm: [8, 0]}\n"),
              "bad.yaml:2: deformation.push_mm: a push of 1.6 x radius_mm or more folds the tissue over itself");
    EXPECT_EQ(error_of("frames: 10\ndeformation: {radius_mm: 5}\n"), "bad.yaml:2: deformation.push_mm: missing");
    EXPECT_EQ(error_of("frames: 10\ntarget: {kind: dots}\n"),
              "bad.yaml:2: target.kind: expected one of white, squares, checkerboard, two_dot, "
              "grid_lines, got 'dots'");
    EXPECT_EQ(
        error_of("frames: 10\ntarget: {kind: two_dot, distances_mm: [30, 40], frames_per_distance: "
                 "[1, 2, 3]}\n"),
        "bad.yaml:2: target.frames_per_distance: expected a number or one number per distance (2)");
    EXPECT_EQ(error_of("frames: 10\ntissue: {image: nothere.png}\n"),
              "bad.yaml:2: tissue.image: no such file: nothere.png");
    EXPECT_EQ(error_of("frames: 10\nendoscope:\n  - {zoom: 9, frames: 3}\n"),
              "bad.yaml:3: endoscope[0].zoom: must be in 0.2..5, got 9");
    EXPECT_EQ(error_of("frames: 10\ntools:\n  - {id: 1, start: {tip_mm: [0, 0, 60]}}\n  - {id: 1, "
                       "start: {tip_mm: [0, 0, 60]}}\n"),
              "bad.yaml:4: tools[1].id: duplicate id 1");
    EXPECT_EQ(error_of("frames: 10\ntools:\n  - start: {marker_mm: [0, 0, 60]}\n"),
              "bad.yaml:3: tools[0].markers: the marker anchor needs markers.count >= 1");
}

TEST(SceneScenario, NotYamlAtAll) {
    const std::string e = error_of("frames: [1, 2\n");
    EXPECT_EQ(e.rfind("bad.yaml:", 0), 0u) << e;
    EXPECT_NE(e.find("not valid YAML"), std::string::npos) << e;
}

TEST(SceneScenario, DefaultsAndOverrides) {
    Scenario s;
    std::string error;
    ASSERT_TRUE(parse_scenario(R"(
frames: 20
size: 1920x1080
light: {from: 0.2, to: 0.9}
factors: {speed: "0-4", distractors: true, level: 3}
tools:
  - {diameter_mm: 10, tip: scissors, jaw: open, start: {yaw_deg: -40, pitch_deg: -20, depth_mm: 90},
     motion: [{dwell: 4}, {pose: {yaw_deg: -30, pitch_deg: -25, depth_mm: 80}, frames: 6, roll_deg: 30}]}
endoscope: [{hold: 5}, {zoom: 0.7, frames: 5}]
)",
                               "ok.yaml", s, error))
        << error;
    EXPECT_EQ(s.name, "ok");
    EXPECT_EQ(s.width, 1920);
    EXPECT_EQ(s.height, 1080);
    EXPECT_EQ(s.light_from, 0.2);
    EXPECT_EQ(s.light_to, 0.9);
    ASSERT_EQ(s.factors.size(), 3u);
    EXPECT_EQ(std::get<std::string>(s.factors[0].second), "0-4");
    EXPECT_EQ(std::get<bool>(s.factors[1].second), true);
    EXPECT_EQ(std::get<double>(s.factors[2].second), 3.0);
    ASSERT_EQ(s.tools.size(), 1u);
    EXPECT_EQ(s.tools[0].diameter_mm, 10);
    EXPECT_TRUE(s.tools[0].start_is_pose);
    ASSERT_EQ(s.tools[0].motion.size(), 2u);
    EXPECT_EQ(*s.tools[0].motion[1].roll_deg, 30);
    scale_durations(s, 3);
    EXPECT_EQ(s.frames, 60);
    EXPECT_EQ(s.tools[0].motion[0].frames, 12);
    EXPECT_EQ(s.endoscope[1].frames, 15);
}

}  // namespace
}  // namespace endotower::scene

#include <filesystem>

#include "endotower/scene/renderer.hpp"

namespace endotower::scene {
namespace {

TEST(SceneScenario, EveryShippedSuiteParsesAndRenders) {
    const std::filesystem::path dir =
        std::filesystem::path(ENDOTOWER_SOURCE_DIR) / "board/sim/scenarios";
    int count = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
        if (e.path().extension() != ".yaml") continue;
        Scenario s;
        std::string error;
        ASSERT_TRUE(load_scenario(e.path().string(), s, error)) << error;
        EXPECT_LE(s.frames, 60) << e.path() << ": CI suites stay small";
        s.width = 640, s.height = 480;  // the first frame is enough to catch a broken scene
        SceneRenderer r;
        ASSERT_TRUE(r.init(s, s.seed, error)) << error;
        Image img;
        FrameTruth t;
        r.render(0, img, t);
        EXPECT_EQ(img.bgr.size(), 640u * 480u * 3u);
        for (const ToolTruth& tool : t.tools)
            EXPECT_TRUE(tool.visible) << e.path() << " tool " << tool.id;
        ++count;
    }
    EXPECT_GE(count, 20);
}

}  // namespace
}  // namespace endotower::scene
