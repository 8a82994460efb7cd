// The SCI end to end: `endotower scene` renders tests/unit/sci/data/sci_ring_dwell.yaml
// (a grasper pointing at the ring menu), `endotower sim` replays it with the handle
// timeline next to it and the likelihood tracker; the trace's "sci" members must give
// exactly the expected sequence: button activation, the tip's highlight of CT and its
// click 2.0 s (50 frames) later, not at 1.9 s; the wheel in the viewer; the sub-ring's
// Main menu by dwell; the wheel to EXIT and the button's click: inactive.
// Through the shipped gesture model (board/sim/scenarios/sci): activation by the
// scissors held 3 s, no menu for tools resting against each other, the open grasper's
// select confirmed by a loop or denied by a stroke, the cross's quadrant menu and off.
// Also: bad sci: board keys are refused with FILE:LINE.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "endotower_command.hpp"

namespace endotower::sci {
namespace {

namespace fs = std::filesystem;
using endotower::test::run_endotower;

fs::path temp_dir(const std::string& name) {
    fs::path d =
        fs::temp_directory_path() / ("endotower_sci_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

struct Step {
    int frame;
    std::string state, menu, highlighted, event;
    bool operator==(const Step&) const = default;
};
std::ostream& operator<<(std::ostream& o, const Step& s) {
    return o << "{" << s.frame << " " << s.state << " " << s.menu << " " << s.highlighted << " "
             << s.event << "}";
}
std::string text(const nlohmann::json& v) {
    return v.is_null() ? "-" : v.get<std::string>();
}

// Renders a scenario of board/sim/scenarios/sci (NAME plus scene options) into dir/scene
// and replays it with the likelihood tracker, the shipped gesture model and the SCI in
// `layout` (three-level unless said), with the handle `events` file (none unless said),
// tracing to dir/trace.jsonl. `models`: the gesture model and the segmenter's pixel model
// (the shipped ones unless said). Empty when both ran, else the failing command's output.
struct GestureModels {
    std::string gestures = ENDOTOWER_SOURCE_DIR "/board/sim/models/gestures.yml";
    std::string pixels = ENDOTOWER_SOURCE_DIR "/board/sim/models/gesture_tool_likelihood.bin";
};
std::string replay_with_gestures(const fs::path& dir, const std::string& scenario,
                                 const std::string& layout = "three_level",
                                 const std::string& events = "''",
                                 const GestureModels& models = {}) {
    const std::string src = ENDOTOWER_SOURCE_DIR;
    auto scene = run_endotower("scene --scenario " + src + "/board/sim/scenarios/sci/" + scenario +
                               " --out " + (dir / "scene").string());
    if (scene.status != 0) return scene.output;
    std::ofstream(dir / "board.yaml")
        << "board: sci_test\nanalysis:\n  stage: none\n  tracker: likelihood\n  tool_model: " << src
        << "/board/sim/models/tool_likelihood.bin\n  gestures:\n    model: " << models.gestures
        << "\n    tool_model: " << models.pixels << "\nsci:\n  layout: " << layout
        << "\n  media: " << src << "/board/sim/sci_media\n";
    auto sim =
        run_endotower("sim --board " + (dir / "board.yaml").string() + " --input " +
                      (dir / "scene/frames").string() + " --events " + events + " --out " +
                      (dir / "o.avi").string() + " --trace " + (dir / "trace.jsonl").string());
    return sim.status == 0 ? std::string() : sim.output;
}

// replay_with_gestures with the ring menu opened by the handle's button at frame 3.
std::string replay_on_the_ring_after_the_button(const fs::path& dir, const std::string& scenario,
                                                const GestureModels& models = {}) {
    std::ofstream(dir / "events.txt") << "frame 3 press\nframe 4 release\n";
    return replay_with_gestures(dir, scenario, "ring", (dir / "events.txt").string(), models);
}

// The models shipped until 2026-11-29: the segmenter on the tracker's pixel model, which
// reads the pale pink sheen of wet tissue as tool, and the network trained on its masks.
// With them the cases of the two rules below (a tissue region beside the tools read as a
// single tool) occur in these scenes; with the shipped pair the tissue regions are
// there but rarely read as a tool (docs/gestures.md, "The segmenter's own pixel model").
// Real video can still give such regions, so the rules stay, tested with these models.
const GestureModels kTrackerPixels{ENDOTOWER_SOURCE_DIR
                                   "/tests/unit/sci/data/gestures_tracker_pixels.yml",
                                   ENDOTOWER_SOURCE_DIR "/board/sim/models/tool_likelihood.bin"};

// The gesture model shipped until 2026-11-29 (late night), trained over one tissue, with
// the shipped pixel model. It reads the grasp of cross_by_grasping.yaml as a triangle,
// then a cross held 1 s, the case of the grasp rule; with the shipped model, trained over
// more tissues, no cross fires there (docs/gestures.md, "More tissues"). A real grasp can
// still be read so, so the rule stays, tested with this model.
const GestureModels kOneTissue{ENDOTOWER_SOURCE_DIR "/tests/unit/sci/data/gestures_one_tissue.yml",
                               ENDOTOWER_SOURCE_DIR
                               "/board/sim/models/gesture_tool_likelihood.bin"};

// Every frame of dir/trace.jsonl as a Step.
std::vector<Step> read_steps(const fs::path& dir) {
    std::vector<Step> every;
    std::ifstream in(dir / "trace.jsonl");
    for (std::string line; std::getline(in, line);) {
        const nlohmann::json j = nlohmann::json::parse(line);
        const nlohmann::json& s = j.at("sci");
        every.push_back({j.at("frame").get<int>(), text(s.at("state")), text(s.at("menu")),
                         text(s.at("highlighted")), text(s.at("event"))});
    }
    return every;
}
std::vector<Step> events_of(const std::vector<Step>& every) {
    std::vector<Step> events;
    for (const Step& s : every)
        if (s.event != "-") events.push_back(s);
    return events;
}

TEST(SciScenario, RingMenuExactSequence) {
    const fs::path dir = temp_dir("ring");
    const std::string src = ENDOTOWER_SOURCE_DIR;
    auto scene =
        run_endotower("scene --scenario " + src +
                      "/tests/unit/sci/data/sci_ring_dwell.yaml --out " + (dir / "scene").string());
    ASSERT_EQ(scene.status, 0) << scene.output;
    std::ofstream(dir / "board.yaml")
        << "board: sci_test\nanalysis:\n  stage: none\n  tracker: likelihood\n"
           "  tool_model: "
        << src
        << "/board/sim/models/tool_likelihood.bin\n"
           "sci:\n  layout: ring\n  media: "
        << src << "/board/sim/sci_media\n";
    auto sim =
        run_endotower("sim --board " + (dir / "board.yaml").string() + " --input " +
                      (dir / "scene/frames").string() + " --events " + src +
                      "/tests/unit/sci/data/sci_ring_dwell_events.txt --out " +
                      (dir / "o.avi").string() + " --trace " + (dir / "trace.jsonl").string());
    ASSERT_EQ(sim.status, 0) << sim.output;

    std::vector<Step> events, every;
    std::ifstream in(dir / "trace.jsonl");
    for (std::string line; std::getline(in, line);) {
        const nlohmann::json j = nlohmann::json::parse(line);
        ASSERT_TRUE(j.contains("sci")) << line;
        const nlohmann::json& s = j["sci"];
        for (const char* k : {"state", "menu", "highlighted", "event"})
            ASSERT_TRUE(s.contains(k)) << k;
        const Step st{j["frame"].get<int>(), text(s["state"]), text(s["menu"]),
                      text(s["highlighted"]), text(s["event"])};
        every.push_back(st);
        if (st.event != "-") events.push_back(st);
    }
    ASSERT_EQ(every.size(), 175u);
    ASSERT_EQ(events.size(), 8u) << ::testing::PrintToString(events);
    // The tip reaches the ring while moving (frames 10-19) and the sub-ring (90-94).
    const int h1 = events[1].frame, h2 = events[4].frame;
    EXPECT_GE(h1, 10);
    EXPECT_LT(h1, 20);
    EXPECT_GE(h2, 90);
    EXPECT_LT(h2, 95);
    const std::vector<Step> expected = {
        {5, "menu", "main", "-", "activate_button"},
        {h1, "highlight", "main", "CT", "highlight"},
        {h1 + 50, "menu", "viewer", "-", "click"},  // 2.0 s at 25 fps
        {85, "menu", "viewer", "-", "image"},
        {h2, "highlight", "viewer", "Main menu", "highlight"},
        {h2 + 50, "menu", "main", "-", "click"},
        {160, "highlight", "main", "EXIT", "wheel"},
        {165, "inactive", "-", "-", "exit"},
    };
    EXPECT_EQ(events, expected);
    // 1.9 s (and 1.96 s) after the highlight: still highlighted, no click.
    EXPECT_EQ(every[h1 + 47], (Step{h1 + 47, "highlight", "main", "CT", "-"}));
    EXPECT_EQ(every[h1 + 49], (Step{h1 + 49, "highlight", "main", "CT", "-"}));
    fs::remove_all(dir);
}

// Activation by gesture (fig. 3.31): board/sim/scenarios/sci/scissors_activation.yaml,
// an open scissors from the lower right held still in the activation area from frame
// 20, rendered and replayed with the shipped gesture model and the likelihood tracker,
// no handle events. The SCI starts activating when the scissors arrive, never cancels,
// and opens the main menu 3.0 s (75 frames at 25 fps) after the hold began, not before:
// the activation_start frame (the scissors' first still frame, 19 or 20) + 75 or 76.
TEST(SciScenario, ScissorsHeldInTheActivationAreaActivateAfterThreeSeconds) {
    const fs::path dir = temp_dir("activation");
    const std::string failed = replay_with_gestures(dir, "scissors_activation.yaml --frames 100");
    ASSERT_TRUE(failed.empty()) << failed;
    const std::vector<Step> events = events_of(read_steps(dir));
    ASSERT_EQ(events.size(), 2u) << ::testing::PrintToString(events);
    EXPECT_EQ(events[0].event, "activation_start");
    EXPECT_EQ(events[0].state, "activating");
    EXPECT_GE(events[0].frame, 19);
    EXPECT_LE(events[0].frame, 20);
    EXPECT_EQ(events[1], (Step{events[1].frame, "menu", "main", "-", "activate_hold"}));
    EXPECT_GE(events[1].frame - events[0].frame, 75);  // 3.0 s
    EXPECT_LE(events[1].frame - events[0].frame, 76);
    fs::remove_all(dir);
}

// Every frame of dir/trace.jsonl has the SCI inactive with no event (no command meant);
// returns each frame's "gesture".
std::vector<nlohmann::json> expect_no_sci_event(const fs::path& dir) {
    std::vector<nlohmann::json> gestures;
    std::ifstream in(dir / "trace.jsonl");
    for (std::string line; std::getline(in, line);) {
        const nlohmann::json j = nlohmann::json::parse(line);
        const nlohmann::json& s = j.at("sci");
        EXPECT_EQ(text(s.at("state")), "inactive") << "frame " << gestures.size();
        EXPECT_EQ(text(s.at("event")), "-") << "frame " << gestures.size();
        gestures.push_back(j.at("gesture"));
    }
    return gestures;
}

// No gesture meant (docs/gestures.md "One arm"): board/sim/scenarios/sci/tools_resting.yaml,
// the 10 mm grasper resting its closed tip on the scissors' closed jaws, both still for
// 2.4 s (the pose of surgery_motion seed 39, where the SCI opened the quadrant menu). Its
// tip window reads as a cross, but a two-tool gesture needs two arms: no gesture fires as
// a cross and the SCI stays inactive, no event at all. Without the rule the quadrant
// menu opens on frame 25, 1 s after the first cross.
TEST(SciScenario, ToolsRestingAgainstEachOtherOpenNoMenu) {
    const fs::path dir = temp_dir("resting");
    const std::string failed = replay_with_gestures(dir, "tools_resting.yaml");
    ASSERT_TRUE(failed.empty()) << failed;
    const std::vector<nlohmann::json> gestures = expect_no_sci_event(dir);
    for (std::size_t f = 0; f < gestures.size(); ++f)
        EXPECT_FALSE(gestures[f].at("fired").get<bool>() &&
                     text(gestures[f].at("label")) == "cross")
            << "frame " << f;
    EXPECT_EQ(gestures.size(), 60u);
    fs::remove_all(dir);
}

// No command meant (docs/sci.md "A cross formed by a grasp"):
// board/sim/scenarios/sci/cross_by_grasping.yaml, the pose of surgery_motion seed 52. An
// open grasper comes over the still scissors (read as a triangle), and closes its jaws
// over them on frame 34: the gesture stage reads and holds a cross, fired, still for
// 2.6 s, but it formed out of the triangle while the tools touched, so the SCI stays
// inactive with no event at all. Without the rule the quadrant menu opens on frame 60.
// Read with the one-tissue model (kOneTissue), which holds that cross.
TEST(SciScenario, ACrossFormedByJawsClosingOverTheOtherToolOpensNoMenu) {
    const fs::path dir = temp_dir("grasping");
    const std::string failed =
        replay_with_gestures(dir, "cross_by_grasping.yaml", "three_level", "''", kOneTissue);
    ASSERT_TRUE(failed.empty()) << failed;
    const std::vector<nlohmann::json> gestures = expect_no_sci_event(dir);
    int triangles = 0, cross_fired = 0;
    for (const nlohmann::json& g : gestures) {
        triangles += text(g.at("label")) == "triangle";
        cross_fired += g.at("fired").get<bool>() && text(g.at("label")) == "cross";
    }
    EXPECT_EQ(gestures.size(), 100u);
    // The case is there: the triangle held first, then the cross held 1 s.
    EXPECT_GE(triangles, 5);
    EXPECT_EQ(cross_fired, 1);
    fs::remove_all(dir);
}

// Gesture commands (fig. 3.32, 3.33): board/sim/scenarios/sci/grasper_confirm.yaml, the
// ring menu opened by the handle's button at frame 3; a grasper comes onto the MRI
// sector (frames 10-20) and opens its jaws there, held still; from frame 55 its tip loops
// once in 1.2 s. The open grasper held 1.0 s (25 frames from its arrival) selects MRI;
// the loop confirms it within the 2 s: MRI's image viewer. No dwell click meanwhile (the
// select comes before the 2 s dwell), nothing else.
TEST(SciScenario, OpenGrasperSelectsAndALoopConfirms) {
    const fs::path dir = temp_dir("confirm");
    const std::string failed = replay_on_the_ring_after_the_button(dir, "grasper_confirm.yaml");
    ASSERT_TRUE(failed.empty()) << failed;
    const std::vector<Step> every = read_steps(dir), events = events_of(every);
    ASSERT_EQ(every.size(), 92u);
    ASSERT_EQ(events.size(), 4u) << ::testing::PrintToString(events);
    const int h = events[1].frame, sel = events[2].frame, done = events[3].frame;
    EXPECT_EQ(events[0], (Step{3, "menu", "main", "-", "activate_button"}));
    EXPECT_EQ(events[1], (Step{h, "highlight", "main", "MRI", "highlight"}));
    EXPECT_GE(h, 11);  // reached while moving in (frames 10-20)
    EXPECT_LE(h, 20);
    EXPECT_EQ(events[2], (Step{sel, "confirm", "main", "MRI", "select"}));
    EXPECT_GE(sel, 45);  // the jaws open from frame 20: held 1.0 s
    EXPECT_LE(sel, 47);
    EXPECT_EQ(events[3], (Step{done, "menu", "viewer", "-", "confirm"}));
    EXPECT_GT(done, 55);        // the loop begins at frame 55
    EXPECT_LT(done, sel + 50);  // within the 2 s
    for (int f = sel; f < done; ++f) EXPECT_EQ(every[f].state, "confirm") << "frame " << f;
    fs::remove_all(dir);
}

// The same select, then a straight stroke across the item and back instead of a loop
// (board/sim/scenarios/sci/grasper_deny.yaml): denied exactly 2.0 s (50 frames) after
// the select, not at 1.96 s; nothing executed, the main menu stays, and the tip, back on
// MRI, does not highlight it again until it has left.
TEST(SciScenario, AStraightStrokeDeniesAfterTwoSeconds) {
    const fs::path dir = temp_dir("deny");
    const std::string failed = replay_on_the_ring_after_the_button(dir, "grasper_deny.yaml");
    ASSERT_TRUE(failed.empty()) << failed;
    const std::vector<Step> every = read_steps(dir), events = events_of(every);
    ASSERT_EQ(every.size(), 100u);
    ASSERT_EQ(events.size(), 4u) << ::testing::PrintToString(events);
    const int sel = events[2].frame;
    EXPECT_EQ(events[0], (Step{3, "menu", "main", "-", "activate_button"}));
    EXPECT_EQ(events[1].event, "highlight");
    EXPECT_EQ(events[1].highlighted, "MRI");
    EXPECT_EQ(events[2], (Step{sel, "confirm", "main", "MRI", "select"}));
    EXPECT_GE(sel, 45);
    EXPECT_LE(sel, 47);
    EXPECT_EQ(every[sel + 49], (Step{sel + 49, "confirm", "main", "MRI", "-"}));
    EXPECT_EQ(events[3], (Step{sel + 50, "menu", "main", "-", "deny"}));
    EXPECT_EQ(every.back(), (Step{99, "menu", "main", "-", "-"}));
    fs::remove_all(dir);
}

// Every frame's gesture regions ("gesture.tools") of dir/trace.jsonl.
std::vector<nlohmann::json> gesture_regions(const fs::path& dir) {
    std::vector<nlohmann::json> frames;
    std::ifstream trace(dir / "trace.jsonl");
    for (std::string line; std::getline(trace, line);)
        frames.push_back(nlohmann::json::parse(line).at("gesture").at("tools"));
    return frames;
}

// A 120-frame cross scenario's only two events: the quadrant menu opening on a frame in
// `open` (first, last), then the SCI turning off on a frame in `off`.
void expect_quadrant_then_off(const fs::path& dir, std::pair<int, int> open,
                              std::pair<int, int> off) {
    const std::vector<Step> every = read_steps(dir), events = events_of(every);
    ASSERT_EQ(every.size(), 120u);
    ASSERT_EQ(events.size(), 2u) << ::testing::PrintToString(events);
    EXPECT_EQ(events[0], (Step{events[0].frame, "menu", "quadrant", "-", "quadrant"}));
    EXPECT_GE(events[0].frame, open.first);
    EXPECT_LE(events[0].frame, open.second);
    EXPECT_EQ(events[1], (Step{events[1].frame, "inactive", "-", "-", "deactivate"}));
    EXPECT_GE(events[1].frame, off.first);
    EXPECT_LE(events[1].frame, off.second);
}

// The cross as a command (fig. 3.34a; board/sim/scenarios/sci/cross_quadrant.yaml, no
// handle events): two closed tools cross their jaws in the middle and hold still; the
// quadrant menu opens 1.0 s after they came to rest, not while they were still moving
// into the cross. Still is within 3 % of the width (19.2 px): the tracked tips come that
// near where they rest on frame 22 and stop on frame 24 or 25, so frames 46-50. They
// part inside the menu's free middle (no highlight), cross again and come to rest on
// frames 88-90: off 1.0 s later, frames 111-115.
TEST(SciScenario, ACrossHeldStillOpensTheQuadrantMenuAndAgainTurnsTheSciOff) {
    const fs::path dir = temp_dir("cross");
    const std::string failed = replay_with_gestures(dir, "cross_quadrant.yaml", "ring");
    ASSERT_TRUE(failed.empty()) << failed;
    expect_quadrant_then_off(dir, {46, 50}, {111, 115});
    fs::remove_all(dir);
}

// The SCI's cross trial 27: beside the crossing, a patch of glints reaching the rim is a
// region of its own, read as scissors. Two regions with a gesture used to be two
// single-tool calls, so the frame had no gesture and no menu opened; a region with a
// two-tool gesture holds both tools, so it is the frame's (docs/gestures.md).
TEST(SciScenario, ACrossBesideAGlintPatchReadAsScissorsOpensTheQuadrantMenu) {
    const fs::path dir = temp_dir("cross_glints");
    const std::string failed =
        replay_with_gestures(dir, "cross_beside_glints.yaml", "ring", "''", kTrackerPixels);
    ASSERT_TRUE(failed.empty()) << failed;
    // The tips come within 3 % of the width of where they rest on frames 22-23 and 93
    // and stop on 25 and 95: the menu and the off 1.0 s later.
    expect_quadrant_then_off(dir, {46, 50}, {116, 119});
    // The case is there: frames with the cross and a second region read as scissors.
    int beside = 0;
    for (const nlohmann::json& tools : gesture_regions(dir)) {
        bool cross = false, scissors = false;
        for (const auto& t : tools) {
            const std::string label = t["label"].is_string() ? t["label"].get<std::string>() : "";
            cross = cross || label == "cross";
            scissors = scissors || label.find("scissors") != std::string::npos;
        }
        beside += cross && scissors;
    }
    EXPECT_GE(beside, 50);
    fs::remove_all(dir);
}

// The SCI's cross trial 84: a 10 mm grasper crosses a 5 mm scissors near the scope. The
// tip window, 8 radii of the grasper's shaft, holds the whole crossing, so no arm leaves
// it and the "No arm" rule took no gesture (no menu); in the window of the thinner shaft
// both shafts leave, and the cross opens the quadrant menu and turns the SCI off again
// (docs/gestures.md, "The thinner shaft's arms").
TEST(SciScenario, ACrossWithATenMillimetreGrasperNearTheScopeOpensTheQuadrantMenu) {
    const fs::path dir = temp_dir("cross_ten_mm");
    const std::string failed = replay_with_gestures(dir, "cross_ten_mm.yaml", "ring");
    ASSERT_TRUE(failed.empty()) << failed;
    // The tips come within 3 % of the width of where they rest on frames 22-23 and 93
    // and stop on 25 and 95: the menu and the off 1.0 s later.
    expect_quadrant_then_off(dir, {46, 50}, {116, 119});
    // The case is there: the crossing's own window has no arm, the thinner one two (74 of
    // the 82 frames whose crossing reads as a cross, with the mask threshold of 170; the
    // other 8 have an arm in their own window).
    int widened = 0;
    for (const nlohmann::json& tools : gesture_regions(dir))
        for (const auto& t : tools)
            widened += t.at("entries") == 2 && t.at("arms") == 0 && t.at("thin_arms") >= 2 &&
                       t.at("label") == "cross";
    EXPECT_GE(widened, 70);
    fs::remove_all(dir);
}

// The events of a select trial's scene on the ring (the button at frame 3) whose open
// grasper selects MRI and whose stroke denies it: activate, highlight MRI, select 1.0 s
// after the jaws opened on it (from frame 22: frames 45-49), deny exactly 2.0 s later.
// Returns the select's frame, 0 when the events are not these four.
int expect_mri_selected_then_denied(const std::vector<Step>& events) {
    if (events.size() != 4u) {
        ADD_FAILURE() << "4 events expected: " << ::testing::PrintToString(events);
        return 0;
    }
    EXPECT_EQ(events[0], (Step{3, "menu", "main", "-", "activate_button"}));
    EXPECT_EQ(events[1].event, "highlight");
    EXPECT_EQ(events[1].highlighted, "MRI");
    const int sel = events[2].frame;
    EXPECT_EQ(events[2], (Step{sel, "confirm", "main", "MRI", "select"}));
    EXPECT_GE(sel, 45);
    EXPECT_LE(sel, 49);
    EXPECT_EQ(events[3], (Step{sel + 50, "menu", "main", "-", "deny"}));
    return sel;
}

// Two regions each read as a single tool are two calls (fig. 3.21) and the frame has no
// gesture, unless one is at the pointer (board/sim/scenarios/sci/grasper_beside_tissue.yaml,
// the SCI's deny trial 98): a 10 mm grasper opens its jaws on MRI while tissue at the far
// side of the view reads as a closed grasper. The grasper's region is at the tracked tip,
// so its open grasper is the frame's: MRI is selected and, after the stroke, denied
// exactly 2.0 s later. Without the rule no select came and the dwell clicked MRI.
TEST(SciScenario, TheOpenGrasperAtThePointerSelectsBesideTissueReadAsATool) {
    const fs::path dir = temp_dir("beside_tissue");
    const std::string failed =
        replay_on_the_ring_after_the_button(dir, "grasper_beside_tissue.yaml", kTrackerPixels);
    ASSERT_TRUE(failed.empty()) << failed;
    const std::vector<Step> every = read_steps(dir), events = events_of(every);
    ASSERT_EQ(every.size(), 135u);
    const int sel = expect_mri_selected_then_denied(events);
    ASSERT_GT(sel, 0);
    // The case is there: before the select the grasper's region reads as an open grasper
    // while another, far from it, reads as a single tool too.
    const std::vector<nlohmann::json> regions = gesture_regions(dir);
    int two_calls = 0;
    for (int f = 22; f < sel; ++f) {
        const auto& t = regions[static_cast<std::size_t>(f)];
        if (t.size() != 2 || t[0].at("label").is_null() || t[1].at("label").is_null()) continue;
        const double dx = t[0].at("tip_px")[0].get<double>() - t[1].at("tip_px")[0].get<double>();
        const double dy = t[0].at("tip_px")[1].get<double>() - t[1].at("tip_px")[1].get<double>();
        two_calls += (t[0].at("label") == "open_grasper" || t[1].at("label") == "open_grasper") &&
                     std::hypot(dx, dy) > 150;
    }
    EXPECT_GE(two_calls, 15);
    fs::remove_all(dir);
}

// An open grasper the network calls at just under 0.5 (board/sim/scenarios/sci/
// grasper_doubtful.yaml, the SCI's held-out deny trial 137): with one bar for every label
// the frame had no gesture and the 2 s dwell clicked MRI. The open grasper commands
// nothing on its own, so its bar is 0.4: MRI is selected and the stroke denies it exactly
// 2.0 s later.
TEST(SciScenario, AnOpenGrasperReadJustUnderHalfSelects) {
    const fs::path dir = temp_dir("doubtful");
    const std::string failed = replay_on_the_ring_after_the_button(dir, "grasper_doubtful.yaml");
    ASSERT_TRUE(failed.empty()) << failed;
    const std::vector<Step> every = read_steps(dir), events = events_of(every);
    ASSERT_EQ(every.size(), 135u);
    const int sel = expect_mri_selected_then_denied(events);
    ASSERT_GT(sel, 0);
    // The case is there: before the select the open grasper is called under 0.5.
    const std::vector<nlohmann::json> regions = gesture_regions(dir);
    int doubtful = 0;
    for (int f = 22; f < sel; ++f)
        for (const auto& t : regions[static_cast<std::size_t>(f)])
            doubtful += t.at("read") == "open_grasper" && t.at("confidence").get<double>() >= 0.4 &&
                        t.at("confidence").get<double>() < 0.5;
    EXPECT_GE(doubtful, 15);
    fs::remove_all(dir);
}

TEST(SciBoard, UnknownKeysAndLayoutsAreRefusedWithFileAndLine) {
    const fs::path dir = temp_dir("board");
    std::ofstream(dir / "a.yaml") << "board: t\nsci:\n  layout: ring\n  dwel_ms: 100\n";
    auto r = run_endotower("sim --board " + (dir / "a.yaml").string() + " --input x --out o.avi");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("a.yaml:4: field 'sci.dwel_ms': unknown key"), std::string::npos)
        << r.output;
    std::ofstream(dir / "b.yaml") << "board: t\nsci:\n  layout: pie\n";
    r = run_endotower("sim --board " + (dir / "b.yaml").string() + " --input x --out o.avi");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("b.yaml:3: field 'sci.layout': unknown layout 'pie' (expected buttons, "
                            "ring or three_level)"),
              std::string::npos)
        << r.output;
    std::ofstream(dir / "c.yaml") << "board: t\nsci:\n  dwell_ms: 50\n";
    r = run_endotower("sim --board " + (dir / "c.yaml").string() + " --input x --out o.avi");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(
        r.output.find("c.yaml:3: field 'sci.dwell_ms': must be between 100 and 60000, got 50"),
        std::string::npos)
        << r.output;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace endotower::sci
