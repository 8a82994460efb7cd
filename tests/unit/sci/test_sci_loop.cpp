// The loop of a select (fig. 3.32) on the tips of rendered trials
// (toolchain/sci-gesture-commands.sh, 640x480, 25 fps; docs/sci.md "The loop on the
// jaws' tip"), as the traces of commit f97578b recorded them from the select on: per
// frame the tracked tip (the cursor) and the tip of the gesture stage's region (the open
// jaws' end, -1 when no gesture is read). The loop is read on the jaws' tip.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

#include "endotower/sci/sci_machine.hpp"

namespace endotower::sci {
namespace {

constexpr hal::Nanos kMs = 1'000'000;
struct Tip {
    double tracked_x, tracked_y, jaws_x, jaws_y;
};

// Trial 7: a 5 mm grasper loops (radius 3.2 mm at 75 mm) from the 11th frame on; its
// steps go in seven directions on either tip.
// Trial 25: a 10 mm grasper's loop of 3.1 mm at 83 mm, 31 px across; the tracked tip,
// further back on the jaws, draws it 17 px high: its steps go in three directions, the
// jaws' tip's in five (the rule of 2026-11-29, six on the tracked tip, denied it).
// Trial 41: a straight stroke across the item and back while the tracked tip jumps 60 px
// to the other jaw and back for nine frames: its steps go in five directions, the jaws'
// tip's in three.
// trial 7: frames 47-96, 0 without a gesture
constexpr Tip kTrial7[] = {
    {469.7, 245.3, 471.4, 246.3}, {469.7, 245.3, 470.5, 247.3}, {469.7, 245.3, 470.6, 247.2},
    {469.7, 245.3, 471.8, 245.6}, {469.7, 245.3, 470.5, 247.3}, {469.7, 245.3, 470.4, 247.2},
    {469.7, 245.3, 471.7, 246.3}, {469.7, 245.3, 471.8, 245.7}, {469.7, 245.3, 471.5, 246.6},
    {469.7, 245.3, 470.3, 248.1}, {469.7, 245.3, 470.5, 247.6}, {477.9, 244.8, 473.9, 252.6},
    {479.9, 250.6, 477.8, 257.5}, {483.0, 250.9, 478.3, 260.9}, {481.6, 256.6, 480.7, 261.6},
    {481.5, 261.2, 482.1, 263.7}, {483.5, 263.2, 482.3, 267.8}, {488.0, 262.2, 485.5, 268.5},
    {489.8, 263.9, 488.3, 269.4}, {493.8, 263.9, 489.9, 272.3}, {496.1, 266.1, 494.8, 272.1},
    {492.6, 274.4, 497.4, 270.5}, {499.3, 266.5, 498.9, 270.9}, {497.8, 271.2, 500.7, 270.5},
    {499.4, 269.8, 503.7, 266.1}, {502.5, 263.9, 503.3, 267.1}, {504.7, 261.9, 505.7, 263.8},
    {507.4, 252.7, 505.3, 260.4}, {503.0, 259.0, 505.6, 256.7}, {502.3, 253.3, 504.4, 254.8},
    {502.0, 251.4, 502.5, 253.1}, {499.3, 250.8, 501.2, 251.0}, {500.6, 244.4, 499.0, 249.4},
    {498.6, 242.4, 497.2, 247.2}, {494.0, 243.4, 495.0, 245.3}, {492.2, 240.5, 491.5, 244.8},
    {488.2, 240.5, 487.5, 244.1}, {482.3, 245.6, 484.8, 245.3}, {484.1, 240.7, 483.1, 245.6},
    {477.2, 248.9, 480.7, 246.6}, {476.7, 248.9, 480.4, 246.6}, {479.0, 245.5, 477.7, 250.3},
    {476.1, 248.7, 476.3, 252.4}, {476.1, 248.7, 477.4, 251.0}, {476.1, 248.7, 477.4, 250.9},
    {476.1, 248.7, 477.8, 250.5}, {476.1, 248.7, 476.9, 251.7}, {476.1, 248.7, 476.4, 252.4},
    {476.1, 248.7, 477.0, 251.6}, {476.1, 248.7, 477.0, 251.6},
};
// trial 25: frames 47-96, 0 without a gesture
constexpr Tip kTrial25[] = {
    {172.4, 216.0, 173.2, 214.4}, {172.2, 216.6, 172.6, 216.1}, {172.6, 215.1, 173.1, 212.9},
    {172.4, 216.0, 172.9, 214.9}, {172.4, 216.0, 173.0, 214.8}, {173.0, 213.9, 172.7, 215.8},
    {172.2, 216.4, 173.2, 213.4}, {172.8, 214.7, 173.1, 214.4}, {172.6, 215.3, 173.5, 211.7},
    {172.8, 214.7, 173.3, 212.1}, {172.4, 216.2, 172.7, 215.8}, {169.4, 215.3, 170.4, 213.6},
    {165.3, 219.9, 166.9, 215.8}, {168.8, 216.9, 169.8, 211.7}, {170.3, 218.9, 171.3, 213.6},
    {172.5, 215.0, 173.1, 214.6}, {174.0, 212.0, 173.4, 216.7}, {174.0, 215.8, 174.2, 218.5},
    {176.1, 214.7, 175.4, 216.6}, {174.6, 217.0, 175.5, 217.1}, {173.9, 221.4, 174.9, 216.0},
    {173.3, 220.6, 173.8, 219.7}, {171.6, 221.7, 172.6, 219.4}, {170.8, 222.2, 170.9, 221.4},
    {168.9, 223.6, 168.8, 223.4}, {166.0, 224.5, 166.3, 223.7}, {163.9, 224.9, 163.8, 224.1},
    {161.6, 225.6, 161.6, 224.8}, {159.3, 224.5, 159.6, 224.2}, {157.0, 226.6, 156.9, 223.2},
    {154.6, 225.5, 154.9, 222.8}, {152.8, 225.2, 153.7, 221.2}, {151.8, 219.5, 151.9, 219.4},
    {150.0, 222.2, 150.6, 217.2}, {149.1, 219.1, 150.1, 214.7}, {148.3, 220.4, 149.4, 215.6},
    {146.5, 222.7, 148.4, 214.8}, {146.1, 227.3, 150.1, 208.9}, {146.8, 224.8, 149.1, 213.4},
    {146.8, 222.9, 150.1, 210.9}, {147.9, 224.0, 151.8, 211.4}, {150.1, 221.4, 152.9, 210.5},
    {152.6, 217.1, 154.4, 211.1}, {153.4, 220.7, 156.5, 211.4}, {154.1, 228.4, 158.3, 213.0},
    {157.4, 225.0, 161.3, 209.9}, {156.5, 226.9, 160.8, 210.8}, {157.0, 225.0, 160.7, 211.4},
    {155.9, 229.1, 160.7, 211.4}, {155.5, 229.9, 160.8, 211.9},
};
// trial 41: frames 47-96, 0 without a gesture
constexpr Tip kTrial41[] = {
    {168.9, 225.5, 168.9, 225.7}, {168.8, 226.0, 168.7, 226.1}, {168.8, 225.5, 168.5, 227.8},
    {168.8, 226.5, 168.7, 225.3}, {168.6, 227.1, 169.2, 225.5}, {168.8, 225.5, 169.2, 224.2},
    {168.8, 226.0, 168.9, 225.3}, {168.8, 226.0, 169.0, 224.4}, {168.8, 226.0, 168.6, 227.9},
    {168.8, 226.0, 168.9, 225.5}, {168.8, 226.0, 168.9, 225.5}, {167.9, 228.0, 168.0, 223.0},
    {166.8, 222.2, 166.3, 228.0}, {166.1, 222.4, 165.9, 222.4}, {165.5, 221.4, 164.7, 223.1},
    {164.7, 211.8, 163.8, 219.1}, {163.7, 214.9, 163.1, 217.6}, {162.4, 217.2, 162.0, 216.6},
    {161.8, 210.1, 160.9, 217.0}, {160.3, 210.7, 160.2, 214.4}, {160.5, 207.9, 159.5, 211.6},
    {221.8, 227.6, 158.9, 209.5}, {221.8, 227.6, 157.4, 149.5}, {214.6, 222.2, 156.8, 156.8},
    {218.6, 222.9, 155.0, 168.2}, {215.3, 218.3, 153.4, 178.2}, {214.6, 222.2, 154.2, 172.7},
    {214.6, 222.2, 155.2, 169.4}, {217.9, 226.9, 150.3, 143.4}, {217.9, 226.9, 155.3, 210.4},
    {156.2, 209.9, 155.7, 210.6}, {156.0, 213.6, 155.5, 212.6}, {156.6, 213.0, 155.8, 213.7},
    {156.7, 209.8, 155.6, 215.7}, {157.0, 211.1, 155.8, 216.1}, {157.0, 213.8, 155.4, 221.4},
    {156.5, 218.4, 155.4, 222.4}, {156.7, 219.5, 155.8, 220.5}, {156.2, 224.0, 155.9, 221.4},
    {156.6, 225.3, 156.2, 222.3}, {156.7, 227.2, 155.9, 226.3}, {156.8, 226.2, 156.4, 224.5},
    {156.6, 225.5, 155.9, 228.1}, {157.0, 225.6, 155.6, 228.2}, {156.7, 226.5, 156.2, 224.3},
    {156.9, 225.9, 156.1, 225.5}, {156.7, 225.3, 156.0, 226.1}, {156.8, 226.7, 156.0, 225.9},
    {156.7, 227.7, 156.3, 224.9}, {156.9, 226.4, 155.9, 226.5},
};

// Activates by the button (three_level layout), fires the open grasper's hold with the
// cursor on "3-D effects" (the select), then plays the rest a frame each 40 ms, read
// with the jaws' tip as the gesture's (or, `jaws` false, no gesture after the select:
// the tracked tip alone). The tips are moved so that the first tracked tip is the
// item's centre. Returns the event that ended the confirm window and its frame from
// the select.
template <std::size_t N>
std::pair<std::string, int> replay(const Tip (&tips)[N], bool jaws = true) {
    SciMachine m;
    m.configure(640, 480);
    const hal::ControlEvent press{hal::ControlEvent::Kind::kButtonPress, 0, 0, 0};
    SciFrame on;
    on.events = {&press, 1};
    m.step(on);
    double dx = 0, dy = 0;
    for (std::size_t k = 0; k < m.menu().count; ++k) {
        const SciItem& i = m.menu().items[k];
        if (i.label == "3-D effects")
            dx = i.x + i.width / 2 - tips[0].tracked_x, dy = i.y + i.height / 2 - tips[0].tracked_y;
    }
    auto frame = [&](hal::Nanos t, const Tip& p, SciGesture g, double held, bool fired) {
        SciFrame f;
        f.t_ns = t;
        if (p.tracked_x >= 0)
            f.tools[0].x = p.tracked_x + dx, f.tools[0].y = p.tracked_y + dy, f.tool_count = 1;
        if (p.jaws_x >= 0 && g != SciGesture::kNone)
            f.gesture = g, f.gesture_x = p.jaws_x + dx, f.gesture_y = p.jaws_y + dy;
        f.gesture_held_ms = held, f.gesture_fired = fired;
        m.step(f);
    };
    frame(40 * kMs, tips[0], SciGesture::kNone, 0, false);
    frame(80 * kMs, tips[0], SciGesture::kOpenGrasper, 0, false);
    frame(1080 * kMs, tips[0], SciGesture::kOpenGrasper, 1000, true);
    EXPECT_EQ(m.event(), "select");
    EXPECT_EQ(
        m.highlighted() >= 0 ? m.menu().items[static_cast<std::size_t>(m.highlighted())].label : "",
        "3-D effects");
    for (int k = 1; k <= 50; ++k) {
        frame(1080 * kMs + k * 40 * kMs,
              tips[std::min<std::size_t>(static_cast<std::size_t>(k), N - 1)],
              jaws ? SciGesture::kOpenGrasper : SciGesture::kNone, jaws ? 1000 + k * 40 : 0, false);
        if (m.event() == "confirm" || m.event() == "deny") return {std::string(m.event()), k};
    }
    return {"", 50};
}

TEST(SciLoop, ALoopOnTheJawsTipConfirms) {
    const auto [event, frame] = replay(kTrial7);
    EXPECT_EQ(event, "confirm");
    EXPECT_GT(frame, 11);  // not before the loop began
}

TEST(SciLoop, ASmallFarLoopConfirms) {
    const auto [event, frame] = replay(kTrial25);
    EXPECT_EQ(event, "confirm");
    EXPECT_GT(frame, 11);
}

TEST(SciLoop, AStrokeOnTheJawsTipDeniesAfterTwoSeconds) {
    const auto [event, frame] = replay(kTrial41);
    EXPECT_EQ(event, "deny");
    EXPECT_EQ(frame, 50);  // exactly 2.0 s after the select
}

// Why the jaws' tip: the same stroke read on the tracked tip alone (no gesture) goes in
// five directions and confirms.
TEST(SciLoop, TheSameStrokeOnTheTrackedTipAloneIsReadAsALoop) {
    const auto [event, frame] = replay(kTrial41, false);
    EXPECT_EQ(event, "confirm");
}

}  // namespace
}  // namespace endotower::sci
