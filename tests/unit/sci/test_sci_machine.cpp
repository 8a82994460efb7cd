// SciMachine on synthetic tool tips, gestures and handle events at exact virtual
// times (25 fps frames, 40 ms apart): activation, dwell clicks at 2.0 s and not 1.9 s,
// confirm/deny, the quadrant menu, menu navigation, wheel, exit.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include "endotower/sci/sci_machine.hpp"
#include "endotower/sci/sci_scene.hpp"

namespace endotower::sci {
namespace {

constexpr hal::Nanos kMs = 1'000'000;
constexpr int kW = 640, kH = 480;

struct Driver {
    SciMachine m;
    hal::Nanos t = 0;
    bool dropout = false;  // the next frames' gesture is held through a dropout
    std::optional<std::pair<double, double>> jaws_at;  // the gesture's tip, if not the tool's
    explicit Driver(SciParams p = {}) : m(p) { m.configure(kW, kH); }

    // One frame at time `at` with the cursor at (x, y) (x < 0: no tool).
    void frame(hal::Nanos at, double x, double y, SciGesture g = SciGesture::kNone,
               double held_ms = 0, bool fired = false, std::vector<hal::ControlEvent> events = {}) {
        SciFrame f;
        t = at;
        f.t_ns = at;
        if (x >= 0) {
            f.tools[0].x = x, f.tools[0].y = y;
            f.tool_count = 1;
        }
        f.gesture = g, f.gesture_held_ms = held_ms, f.gesture_fired = fired;
        f.gesture_x = jaws_at ? jaws_at->first : x, f.gesture_y = jaws_at ? jaws_at->second : y;
        f.gesture_dropout = dropout;
        for (auto& e : events) e.time_ns = at;
        f.events = events;
        m.step(f);
    }
    // One frame with the tracked tip at (x, y) and the gesture's region tip (the jaws')
    // at (jx, jy): the open grasper held `held_ms`, fired or not.
    void jaws(hal::Nanos at, double x, double y, double jx, double jy, double held_ms, bool fired) {
        jaws_at = {jx, jy};
        frame(at, x, y, SciGesture::kOpenGrasper, held_ms, fired);
        jaws_at.reset();
    }
    void press(hal::Nanos at, double x, double y) {
        frame(at, x, y, SciGesture::kNone, 0, false,
              {{hal::ControlEvent::Kind::kButtonPress, 0, 0, 0}});
    }
    void wheel(hal::Nanos at, int delta) {
        frame(at, kW / 2.0, kH / 2.0, SciGesture::kNone, 0, false,
              {{hal::ControlEvent::Kind::kWheel, 0, static_cast<std::int16_t>(delta), 0}});
    }
    std::string menu() const { return std::string(to_string(m.menu().id)); }
    std::string lit() const {
        return m.highlighted() < 0 ? "" : std::string(m.menu().items[m.highlighted()].label);
    }
    std::string event() const { return std::string(m.event()); }
    // Activates by the button, rests the tip on item `label` and fires the open grasper's
    // 1 s hold there (t = 1 s): the select. Returns the item's centre.
    std::pair<double, double> select(const std::string& label) {
        press(0, kW / 2.0, kH / 2.0);
        const auto [x, y] = at(label);
        frame(40 * kMs, x, y);
        frame(1000 * kMs, x, y, SciGesture::kOpenGrasper, 1000, true);
        return {x, y};
    }
    // The tip loops from (x, y), one frame each 40 ms, `step_deg` of the circle of
    // `radius` px a frame, for at most `frames` frames: the menu the confirm opened (the
    // time is then in t), or "" when none came.
    std::string loop(double x, double y, double radius, double step_deg, int frames) {
        for (int k = 1; k <= frames; ++k) {
            const double a = k * step_deg * M_PI / 180;
            frame(t + 40 * kMs, x + radius * std::sin(a), y - radius * (1 - std::cos(a)));
            if (event() == "confirm") return menu();
        }
        return "";
    }
    // The centre of item `label` of the current menu.
    std::pair<double, double> at(const std::string& label) const {
        for (std::size_t k = 0; k < m.menu().count; ++k) {
            const SciItem& i = m.menu().items[k];
            if (i.label != label) continue;
            if (!i.sector) return {i.x + i.width / 2, i.y + i.height / 2};
            const double a = (i.start_deg + i.end_deg) / 2 * M_PI / 180,
                         r = (i.r_inner + std::min(i.r_outer, i.r_inner + 60)) / 2;
            return {i.cx + r * std::cos(a), i.cy + r * std::sin(a)};
        }
        ADD_FAILURE() << "no item " << label << " in " << menu();
        return {0, 0};
    }
    // Rests the tip on `label` from `from` until the click; returns the click time.
    hal::Nanos dwell(const std::string& label, hal::Nanos from) {
        const auto [x, y] = at(label);
        const std::string before = menu();
        for (hal::Nanos k = from;; k += 40 * kMs) {
            frame(k, x, y);
            if (event() == "click" || event() == "exit") return k - from;
            if (k - from > 5000 * kMs) return -1;
        }
    }
};

TEST(SciMachine, StartsInactiveAndButtonActivates) {
    Driver d;
    d.frame(0, 320, 240);
    EXPECT_EQ(d.m.state(), SciState::kInactive);
    EXPECT_EQ(d.event(), "");
    d.press(40 * kMs, 320, 240);
    EXPECT_EQ(d.m.state(), SciState::kMenu);
    EXPECT_EQ(d.menu(), "main");
    EXPECT_EQ(d.event(), "activate_button");
}

TEST(SciMachine, DwellClicksAtTwoSecondsNotOnePointNine) {
    Driver d;
    d.press(0, 320, 240);
    const auto [x, y] = d.at("Patient record");
    d.frame(1000 * kMs, x, y);
    EXPECT_EQ(d.event(), "highlight");
    EXPECT_EQ(d.m.state(), SciState::kHighlight);
    EXPECT_EQ(d.lit(), "Patient record");
    d.frame(2900 * kMs, x, y);  // 1.9 s on the item
    EXPECT_EQ(d.event(), "");
    EXPECT_EQ(d.m.state(), SciState::kHighlight);
    EXPECT_NEAR(d.m.dwell_fraction(), 0.95, 1e-12);
    EXPECT_EQ(d.menu(), "main");
    d.frame(2999 * kMs, x, y);  // 1.999 s
    EXPECT_EQ(d.menu(), "main");
    d.frame(3000 * kMs, x, y);  // 2.0 s
    EXPECT_EQ(d.event(), "click");
    EXPECT_EQ(d.menu(), "patient_record");
    EXPECT_EQ(d.m.state(), SciState::kMenu);
}

TEST(SciMachine, DwellIsConfigurableAndRestartsOnAnotherItem) {
    SciParams p;
    p.dwell_ms = 1000;
    Driver d(p);
    d.press(0, 320, 240);
    const auto a = d.at("Patient record"), b = d.at("3-D effects");
    d.frame(40 * kMs, a.first, a.second);
    d.frame(800 * kMs, b.first, b.second);  // moved on: a new dwell
    EXPECT_EQ(d.event(), "highlight");
    d.frame(1040 * kMs, b.first, b.second);
    EXPECT_EQ(d.menu(), "main");
    d.frame(1800 * kMs, b.first, b.second);
    EXPECT_EQ(d.event(), "click");
    EXPECT_EQ(d.menu(), "3d_effects");
}

TEST(SciMachine, AfterAClickTheTipMustLeaveBeforeTheNextDwell) {
    Driver d;
    d.press(0, 320, 240);
    // "Preoperative images" and the submenu's "CT" are in the same place.
    ASSERT_EQ(d.dwell("Preoperative images", 40 * kMs), 2000 * kMs);
    EXPECT_EQ(d.menu(), "preoperative_images");
    const auto [x, y] = d.at("CT");
    const hal::Nanos t0 = d.t;
    for (hal::Nanos t = t0 + 40 * kMs; t < t0 + 4000 * kMs; t += 40 * kMs) d.frame(t, x, y);
    EXPECT_EQ(d.menu(), "preoperative_images");
    EXPECT_EQ(d.lit(), "");
    d.frame(d.t + 40 * kMs, 320, 240);  // off the items
    EXPECT_EQ(d.dwell("CT", d.t + 40 * kMs), 2000 * kMs);
    EXPECT_EQ(d.menu(), "viewer");
    EXPECT_EQ(d.m.modality(), SciModality::kCt);
}

// The tracked tip of a tool held on an item's edge trembles across it. The item stays
// until the tip is `leave_margin_fraction` (0.02 x 640 = 12.8 px) outside it: 8 px out
// every other frame keeps the highlight and the dwell, which clicks at exactly 2.0 s;
// 14 px out leaves it.
TEST(SciMachine, ATipTremblingAcrossAnItemsEdgeKeepsItsDwell) {
    Driver d;
    d.press(0, 320, 240);
    const SciItem& item = d.m.menu().items[static_cast<std::size_t>(
        d.m.menu().hit(static_cast<float>(d.at("Patient record").first),
                       static_cast<float>(d.at("Patient record").second)))];
    const double edge = item.x + item.width, y = item.y + item.height / 2;
    d.frame(40 * kMs, edge - 2, y);
    EXPECT_EQ(d.event(), "highlight");
    for (int k = 2; k < 51; ++k) {
        d.frame(k * 40 * kMs, k % 2 ? edge + 8 : edge - 2, y);
        ASSERT_EQ(d.event(), "") << "frame " << k;
        ASSERT_EQ(d.lit(), "Patient record") << "frame " << k;
    }
    d.frame(51 * 40 * kMs, edge + 8, y);  // 2.0 s after the highlight
    EXPECT_EQ(d.event(), "click");
    EXPECT_EQ(d.menu(), "patient_record");

    Driver e;
    e.press(0, 320, 240);
    e.frame(40 * kMs, edge - 2, y);
    e.frame(80 * kMs, edge + 12, y);
    EXPECT_EQ(e.lit(), "Patient record");
    e.frame(120 * kMs, edge + 14, y);
    EXPECT_EQ(e.event(), "unhighlight");
}

// SciMenu::near: an item grown by the margin; a ring sector radially and by that arc
// at the point's radius. With no margin it is hit().
TEST(SciMenu, NearIsTheItemGrownByTheMargin) {
    const SciMenuTable t = build_menus(SciLayout::kRing, kW, kH);
    const SciMenu& ring = t[static_cast<std::size_t>(MenuId::kMain)];
    std::size_t k = 0;
    while (k < ring.count && !ring.items[k].sector) ++k;
    ASSERT_LT(k, ring.count);
    const SciItem& s = ring.items[k];
    const float mid = (s.start_deg + s.end_deg) / 2 * static_cast<float>(M_PI) / 180;
    auto polar = [&](float r, float a) {
        return std::pair<float, float>{s.cx + r * std::cos(a), s.cy + r * std::sin(a)};
    };
    auto [ox, oy] = polar(s.r_outer + 9, mid);  // 9 px outside the outer radius
    EXPECT_EQ(ring.hit(ox, oy), -1);
    EXPECT_TRUE(ring.near(k, ox, oy, 10));
    EXPECT_FALSE(ring.near(k, ox, oy, 8));
    const float r = (s.r_inner + s.r_outer) / 2, end = s.end_deg * static_cast<float>(M_PI) / 180;
    auto [ax, ay] = polar(r, end + 9 / r);  // 9 px of arc past the end
    EXPECT_NE(ring.hit(ax, ay), static_cast<int>(k));
    EXPECT_TRUE(ring.near(k, ax, ay, 10));
    EXPECT_FALSE(ring.near(k, ax, ay, 8));
    auto [cx, cy] = polar(r, mid);
    EXPECT_EQ(ring.hit(cx, cy), static_cast<int>(k));
    EXPECT_TRUE(ring.near(k, cx, cy, 0));
}

TEST(SciMachine, ScissorsHeldThreeSecondsInTheAreaActivates) {
    Driver d;
    // Outside the area (top of the image): never.
    for (int k = 0; k <= 100; ++k) d.frame(k * 40 * kMs, 320, 100, SciGesture::kScissors, k * 40.0);
    EXPECT_EQ(d.m.state(), SciState::kInactive);
    // Another gesture inside the area: never.
    for (int k = 0; k <= 100; ++k)
        d.frame((200 + k) * 40 * kMs, 320, 450, SciGesture::kOpenGrasper, k * 40.0);
    EXPECT_EQ(d.m.state(), SciState::kInactive);
    const hal::Nanos t0 = 400 * 40 * kMs;
    d.frame(t0, 320, 450, SciGesture::kScissors, 0);
    EXPECT_EQ(d.event(), "activation_start");
    EXPECT_EQ(d.m.state(), SciState::kActivating);
    for (int k = 1; k < 75; ++k)
        d.frame(t0 + k * 40 * kMs, 320, 450, SciGesture::kScissors, k * 40.0);
    EXPECT_EQ(d.m.state(), SciState::kActivating);  // 2.96 s
    d.frame(t0 + 3000 * kMs, 320, 450, SciGesture::kScissors, 3000.0);
    EXPECT_EQ(d.event(), "activate_hold");
    EXPECT_EQ(d.menu(), "main");
}

TEST(SciMachine, MovingTheScissorsRestartsTheActivation) {
    Driver d;
    for (int k = 0; k < 50; ++k) d.frame(k * 40 * kMs, 320, 450, SciGesture::kScissors, k * 40.0);
    // The gesture stage restarted its hold (the tip moved): so does the SCI.
    for (int k = 0; k < 75; ++k)
        d.frame((50 + k) * 40 * kMs, 330, 450, SciGesture::kScissors, k * 40.0);
    EXPECT_EQ(d.m.state(), SciState::kActivating);
    d.frame(125 * 40 * kMs, 330, 450, SciGesture::kScissors, 3000.0);
    EXPECT_EQ(d.event(), "activate_hold");
    // Leaving the area cancels.
    Driver e;
    e.frame(0, 320, 450, SciGesture::kScissors, 0);
    e.frame(40 * kMs, 320, 300, SciGesture::kScissors, 40);
    EXPECT_EQ(e.event(), "activation_cancel");
    EXPECT_EQ(e.m.state(), SciState::kInactive);
}

// Open grasper on a highlighted item selects; a loop of the tip within 2 s confirms.
TEST(SciMachine, OpenGrasperSelectsAndALoopConfirms) {
    Driver d;
    const auto [x, y] = d.select("3-D effects");
    EXPECT_EQ(d.event(), "select");
    EXPECT_EQ(d.m.state(), SciState::kConfirm);
    // A circle of radius 40 px in 1.2 s (30 frames, 12 degrees each).
    EXPECT_EQ(d.loop(x, y, 40, 12, 30), "3d_effects");
    EXPECT_LT(d.t, 3000 * kMs);
}

// A small loop (12 px radius: a 3 mm circle at 85 mm depth at 480 rows) in 1 s (14.4
// degrees a frame) still confirms: on the 160 ms mean its steps pass the jitter floor
// (7.2 px) every two or three frames, in six directions before the turn is done.
TEST(SciMachine, ASmallLoopConfirms) {
    Driver d;
    const auto [x, y] = d.select("3-D effects");
    ASSERT_EQ(d.m.state(), SciState::kConfirm);
    const hal::Nanos from = d.t;
    EXPECT_EQ(d.loop(x, y, 12, 14.4, 25), "3d_effects");
    EXPECT_LE(d.t - from, 1000 * kMs);
}

// The tip read back and forth (an open grasper's tracked tip jumps between the jaw ends
// and the head by more than the jitter floor): every step nearly reverses the
// heading, by +170 degrees here. Summed step by step, two such steps made 340 degrees, a
// "loop" (rendered deny trials confirmed so, toolchain/sci-gesture-commands.sh); on the
// tip's 160 ms mean the jumps are no motion: deny.
TEST(SciMachine, ATipJumpingBackAndForthIsNoLoop) {
    Driver d;
    const auto [x, y] = d.select("3-D effects");
    ASSERT_EQ(d.m.state(), SciState::kConfirm);
    double px = x, py = y;
    for (int k = 1; k < 50; ++k) {
        const double a = k * 170.0 * M_PI / 180;
        px += 11 * std::cos(a), py += 11 * std::sin(a);
        d.frame(1000 * kMs + k * 40 * kMs, px, py);
        ASSERT_EQ(d.m.state(), SciState::kConfirm) << "frame " << k;
    }
    d.frame(3000 * kMs, x, y);
    EXPECT_EQ(d.event(), "deny");
}

// A deny, then the same item selected again: the second loop is read on its own path.
TEST(SciMachine, AfterADenyASecondSelectAndLoopConfirms) {
    Driver d;
    const auto [x, y] = d.select("3-D effects");
    for (int k = 1; k <= 50; ++k) d.frame(1000 * kMs + k * 40 * kMs, x + 0.5 * k, y);
    ASSERT_EQ(d.event(), "deny");
    d.frame(3100 * kMs, x + 0.3 * kW, y);  // away, and back onto the item
    d.frame(3140 * kMs, x, y);
    ASSERT_EQ(d.lit(), "3-D effects");
    d.frame(4140 * kMs, x, y, SciGesture::kOpenGrasper, 1000, true);
    ASSERT_EQ(d.event(), "select");
    EXPECT_EQ(d.loop(x, y, 40, 12, 30), "3d_effects");
}

// Opening the jaws moves the tracked tip back towards the head, here off the item the
// surgeon holds the tool on: the open grasper whose hold began on the item selects it.
TEST(SciMachine, OpenGrasperSelectsTheItemItsHoldBeganOn) {
    Driver d;
    d.press(0, 320, 240);
    const auto [x, y] = d.at("3-D effects");
    d.frame(40 * kMs, x, y);
    ASSERT_EQ(d.lit(), "3-D effects");
    d.frame(80 * kMs, x + 0.3 * kW, y, SciGesture::kOpenGrasper, 0);
    EXPECT_EQ(d.event(), "unhighlight");
    d.frame(1080 * kMs, x + 0.3 * kW, y, SciGesture::kOpenGrasper, 1000, true);
    EXPECT_EQ(d.event(), "select");
    EXPECT_EQ(d.lit(), "3-D effects");
    EXPECT_EQ(d.m.state(), SciState::kConfirm);
}

// Also one the tip left up to the select grace (200 ms) before the hold began: the
// hold is dated from the first frame read as an open grasper, which can come that much
// after the jaws opened and moved the tracked tip (docs/sci.md, "Select and loop").
TEST(SciMachine, OpenGrasperSelectsAnItemLeftJustBeforeItsHold) {
    Driver d;
    d.press(0, 320, 240);
    const auto [x, y] = d.at("3-D effects");
    d.frame(40 * kMs, x, y);
    d.frame(80 * kMs, x + 0.3 * kW, y);
    EXPECT_EQ(d.event(), "unhighlight");
    d.frame(280 * kMs, x + 0.3 * kW, y, SciGesture::kOpenGrasper, 0);  // 200 ms after
    d.frame(1280 * kMs, x + 0.3 * kW, y, SciGesture::kOpenGrasper, 1000, true);
    EXPECT_EQ(d.event(), "select");
    EXPECT_EQ(d.lit(), "3-D effects");
}

// But not an item the tip had left longer before the hold began (240 ms, here).
TEST(SciMachine, OpenGrasperDoesNotSelectAnItemLeftBeforeItsHold) {
    Driver d;
    d.press(0, 320, 240);
    const auto [x, y] = d.at("3-D effects");
    d.frame(40 * kMs, x, y);
    d.frame(80 * kMs, x + 0.3 * kW, y);
    EXPECT_EQ(d.event(), "unhighlight");
    d.frame(320 * kMs, x + 0.3 * kW, y, SciGesture::kOpenGrasper, 0);
    d.frame(1320 * kMs, x + 0.3 * kW, y, SciGesture::kOpenGrasper, 1000, true);
    EXPECT_EQ(d.event(), "");
    EXPECT_EQ(d.m.state(), SciState::kMenu);
}

// The open jaws' end is where the surgeon points; the tracked tip of open jaws can sit
// 40-60 px back along the shaft, on no item (held-out trials 124, 140, 212: no select,
// nothing happened) or on the next one (trial 250: the loop executed EXIT for CT). The
// item under the jaws' tip at the fire is the one selected.
TEST(SciMachine, OpenGrasperSelectsTheItemUnderItsJaws) {
    Driver d;
    d.press(0, 320, 240);
    const auto [x, y] = d.at("3-D effects");
    const auto [ox, oy] = d.at("Patient record");
    d.jaws(40 * kMs, ox, oy, x, y, 0, false);  // the tracked tip on the item before
    EXPECT_EQ(d.lit(), "Patient record");
    d.jaws(1040 * kMs, ox, oy, x, y, 1000, true);
    EXPECT_EQ(d.event(), "select");
    EXPECT_EQ(d.lit(), "3-D effects");
    EXPECT_EQ(d.m.state(), SciState::kConfirm);
}

TEST(SciMachine, OpenGrasperSelectsUnderItsJawsWithTheCursorOnNoItem) {
    Driver d;
    d.press(0, 320, 240);
    const auto [x, y] = d.at("3-D effects");
    d.jaws(40 * kMs, 320, 240, x, y, 0, false);
    EXPECT_EQ(d.lit(), "");
    d.jaws(1040 * kMs, 320, 240, x, y, 1000, true);
    EXPECT_EQ(d.event(), "select");
    EXPECT_EQ(d.lit(), "3-D effects");
}

// But the wheel's highlight is the surgeon's choice: the jaws elsewhere do not change it.
TEST(SciMachine, OpenGrasperSelectsTheWheelsHighlightWhereverItsJaws) {
    Driver d;
    d.press(0, 320, 240);
    d.wheel(40 * kMs, +1);
    ASSERT_EQ(d.lit(), "Preoperative images");
    const auto [x, y] = d.at("3-D effects");
    d.jaws(80 * kMs, 320, 240, x, y, 0, false);
    d.jaws(1080 * kMs, 320, 240, x, y, 1000, true);
    EXPECT_EQ(d.event(), "select");
    EXPECT_EQ(d.lit(), "Preoperative images");
}

TEST(SciMachine, AnyOtherMotionDeniesAfterTwoSeconds) {
    Driver d;
    const auto [x, y] = d.select("3-D effects");
    // A straight stroke to the right and back: no loop.
    for (int k = 1; k < 50; ++k)
        d.frame(1000 * kMs + k * 40 * kMs, x + 4.0 * (k < 25 ? k : 50 - k), y);
    EXPECT_EQ(d.m.state(), SciState::kConfirm);  // 1.96 s
    d.frame(3000 * kMs, x, y);
    EXPECT_EQ(d.event(), "deny");
    EXPECT_EQ(d.menu(), "main");
    EXPECT_EQ(d.m.state(), SciState::kMenu);
}

TEST(SciMachine, CrossHeldOneSecondOpensTheQuadrantMenuAndAgainDeactivates) {
    Driver d;
    d.frame(0, 320, 240, SciGesture::kCross, 0);
    d.frame(960 * kMs, 320, 240, SciGesture::kCross, 960);
    EXPECT_EQ(d.m.state(), SciState::kInactive);
    d.frame(1000 * kMs, 320, 240, SciGesture::kCross, 1000);
    EXPECT_EQ(d.event(), "quadrant");
    EXPECT_EQ(d.menu(), "quadrant");
    // Still held: nothing more until the cross is released and formed again.
    d.frame(3000 * kMs, 320, 240, SciGesture::kCross, 3000);
    EXPECT_EQ(d.menu(), "quadrant");
    const auto [x, y] = d.at("Open MRI");
    d.frame(3040 * kMs, 320, 240);
    EXPECT_EQ(d.dwell("Open MRI", 3080 * kMs), 2000 * kMs);
    EXPECT_EQ(d.menu(), "viewer");
    EXPECT_EQ(d.m.modality(), SciModality::kMri);
    d.frame(d.t + 40 * kMs, x, y, SciGesture::kCross, 0);
    d.frame(d.t + 1000 * kMs, x, y, SciGesture::kCross, 1000);
    EXPECT_EQ(d.event(), "deactivate");
    EXPECT_EQ(d.m.state(), SciState::kInactive);
}

// A command is taken on a frame that shows its gesture, not in the dropout frames the
// gesture stage holds it through (GestureFrame::dropout): a crossing read as a cross
// whose 1 s ran out two frames after the tools parted (surgery_motion seed 81) opens
// nothing; a cross misread in the frame at 1 s opens the menu in the next; the
// scissors' 3 s activation likewise.
TEST(SciMachine, ACommandWaitsForAFrameThatShowsItsGesture) {
    Driver parted;
    for (int k = 0; k < 24; ++k) parted.frame(k * 40 * kMs, 320, 240, SciGesture::kCross, k * 40.0);
    parted.dropout = true;
    for (int k = 24; k <= 28; ++k)
        parted.frame(k * 40 * kMs, 320, 240, SciGesture::kCross, k * 40.0);  // to 1.12 s
    EXPECT_EQ(parted.m.state(), SciState::kInactive);
    parted.dropout = false;
    parted.frame(29 * 40 * kMs, 320, 240);  // the hold ended: no gesture
    for (int k = 30; k < 100; ++k) {
        parted.frame(k * 40 * kMs, 320, 240);
        EXPECT_EQ(parted.m.state(), SciState::kInactive) << k;
    }

    // Held still at (320, y) for `frames` frames, misread in the next (the hold time),
    // shown again in the one after: the state after the misread frame, the last event.
    const auto misread_at_the_hold_time = [](SciGesture g, double y, int frames) {
        Driver d;
        for (int k = 0; k < frames; ++k) d.frame(k * 40 * kMs, 320, y, g, k * 40.0);
        d.dropout = true;
        d.frame(frames * 40 * kMs, 320, y, g, frames * 40.0);
        const SciState misread = d.m.state();
        d.dropout = false;
        d.frame((frames + 1) * 40 * kMs, 320, y, g, (frames + 1) * 40.0);
        return std::pair{misread, d.event()};
    };
    const auto [cross_misread, cross_event] = misread_at_the_hold_time(SciGesture::kCross, 240, 25);
    EXPECT_EQ(cross_misread, SciState::kInactive);  // 1.0 s, misread
    EXPECT_EQ(cross_event, "quadrant");             // 1.04 s
    const auto [scissors_misread, scissors_event] =
        misread_at_the_hold_time(SciGesture::kScissors, 450, 75);
    EXPECT_EQ(scissors_misread, SciState::kActivating);  // 3.0 s, misread
    EXPECT_EQ(scissors_event, "activate_hold");          // 3.04 s
}

// Two tools crossed (the gesture stage calls "cross" and its hold runs on, since the
// crossing does not move) while one slides along its shaft: surgery, not a command. The
// quadrant menu opens only once both tips have been still for the cross hold, exactly
// 1.0 s after the sliding tool stopped (still: within 0.03 x 640 = 19.2 px).
TEST(SciMachine, CrossWithASlidingToolIsNoCommand) {
    SciMachine m;
    m.configure(kW, kH);
    auto step = [&](hal::Nanos t, double x2, double y2, bool both = true) {
        SciFrame f;
        f.t_ns = t;
        f.tool_count = both ? 2 : 1;
        f.tools[0].x = 300, f.tools[0].y = 260;
        f.tools[1].x = x2, f.tools[1].y = y2;
        f.gesture = SciGesture::kCross;
        f.gesture_held_ms = static_cast<double>(t) / 1e6;  // one unbroken hold from t = 0
        f.gesture_x = 320, f.gesture_y = 250;
        m.step(f);
        return std::string(m.event());
    };
    // 0 .. 1.88 s: the second tip slides 8 px a frame, so its still hold restarts every
    // third frame (24 px > 19.2 px), the last time on frame 48, where it stops.
    hal::Nanos t = 0;
    for (int k = 0; k < 48; ++k, t += 40 * kMs) {
        EXPECT_EQ(step(t, 200 + 8.0 * k, 300), "") << "frame " << k;
        EXPECT_EQ(m.state(), SciState::kInactive);
    }
    // It stops on frame 48 (t = 1.92 s); a tremor of 15 px is still, and so is a tool the
    // tracker drops for a frame now and then (crossed shafts merge).
    const double x2 = 200 + 8.0 * 48, y2 = 300;
    const hal::Nanos stopped = t;
    for (;; t += 40 * kMs) {
        const hal::Nanos k = t / (40 * kMs);
        const std::string e = step(t, x2 + (k % 2 ? 15.0 : 0.0), y2, k % 5 != 1);
        if (t - stopped < 1000 * kMs) {
            ASSERT_EQ(e, "") << "at " << (t - stopped) / kMs << " ms after stopping";
            continue;
        }
        EXPECT_EQ(e, "quadrant");
        EXPECT_EQ(t - stopped, 1000 * kMs);
        break;
    }
    EXPECT_EQ(std::string(to_string(m.menu().id)), "quadrant");
}

// The gesture stage dates a cross from its first frame, through a few frames that showed
// something else (GestureHold). Where the tools were still coming together in those
// frames, the quadrant menu waits for 1.0 s of stillness from their last motion, not from
// the date the cross got: here the second tip slides 20 px a frame (more than the 19.2 px
// of stillness) until 200 ms, and the cross, first read at 200 ms, is dated from 0.
TEST(SciMachine, ACrossDatedBackWaitsForTheToolsLastMotion) {
    SciMachine m;
    m.configure(kW, kH);
    auto step = [&](hal::Nanos t, double x2, SciGesture g, double held_ms) {
        SciFrame f;
        f.t_ns = t;
        f.tool_count = 2;
        f.tools[0].x = 300, f.tools[0].y = 260;
        f.tools[1].x = x2, f.tools[1].y = 300;
        f.gesture = g;
        f.gesture_held_ms = held_ms;
        f.gesture_x = 320, f.gesture_y = 250;
        m.step(f);
        return std::string(m.event());
    };
    for (int k = 0; k < 5; ++k)
        EXPECT_EQ(step(k * 40 * kMs, 200 + 20.0 * k, SciGesture::kNone, 0), "");
    const double x2 = 200 + 20.0 * 5;  // the last motion: t = 200 ms
    for (hal::Nanos t = 200 * kMs; t < 1200 * kMs; t += 40 * kMs)
        ASSERT_EQ(step(t, x2, SciGesture::kCross, static_cast<double>(t) / 1e6), "")
            << "at " << t / kMs << " ms";
    EXPECT_EQ(step(1200 * kMs, x2, SciGesture::kCross, 1200), "quadrant");
    EXPECT_EQ(std::string(to_string(m.menu().id)), "quadrant");
}

// One frame of two tools whose tips are at (300 + dx, 260) and (340 + dx, 300), the
// gesture's between them; the machine's event.
std::string two_tools(SciMachine& m, hal::Nanos t, SciGesture g, double held_ms, bool touching,
                      double dx = 0) {
    SciFrame f;
    f.t_ns = t;
    f.tool_count = 2;
    f.tools[0].x = 300 + dx, f.tools[0].y = 260;
    f.tools[1].x = 340 + dx, f.tools[1].y = 300;
    f.gesture = g, f.gesture_held_ms = held_ms, f.tools_touching = touching;
    f.gesture_x = 320 + dx, f.gesture_y = 250;
    m.step(f);
    return std::string(m.event());
}

double ms_since(hal::Nanos t, hal::Nanos since) {
    return static_cast<double>(t - since) / 1e6;
}

// A triangle (the grasper's jaws open across the scissors) whose jaws close over the
// other tool becomes a cross without the tools parting: a grasp, not a command, however
// long it is held still (surgery_motion seed 52). Contact lost for five frames (the last
// of them 200 ms after the last touching one, part_ms) is the segmentation's; a frame
// 240 ms after it, and the tools have parted: a cross formed then is a command, the
// quadrant menu exactly 1.0 s later.
TEST(SciMachine, ACrossFormedByJawsClosingOverTheOtherToolIsAGrasp) {
    SciMachine m;
    m.configure(kW, kH);
    hal::Nanos t = 0;
    for (; t < 800 * kMs; t += 40 * kMs)
        EXPECT_EQ(two_tools(m, t, SciGesture::kOpenCrossing, ms_since(t, 0), true), "");
    for (; t < 1000 * kMs; t += 40 * kMs)  // 800..960: contact lost, 960 = 760 + 200
        EXPECT_EQ(two_tools(m, t, SciGesture::kNone, 0, false), "");
    // The jaws close: a cross, its hold from 1000 ms, still to 3.0 s.
    for (; t <= 3000 * kMs; t += 40 * kMs) {
        ASSERT_EQ(two_tools(m, t, SciGesture::kCross, ms_since(t, 1000 * kMs), true), "")
            << "at " << t / kMs << " ms";
        ASSERT_EQ(m.state(), SciState::kInactive);
    }
    // The tools part (3040..3240, the last 240 ms after 3000), then cross again, closed.
    for (; t < 3280 * kMs; t += 40 * kMs)
        EXPECT_EQ(two_tools(m, t, SciGesture::kNone, 0, false), "");
    const hal::Nanos formed = t;
    for (; t < formed + 1000 * kMs; t += 40 * kMs)
        ASSERT_EQ(two_tools(m, t, SciGesture::kCross, ms_since(t, formed), true), "");
    EXPECT_EQ(two_tools(m, t, SciGesture::kCross, 1000, true), "quadrant");
    EXPECT_EQ(std::string(to_string(m.menu().id)), "quadrant");
}

// A grasp stays a grasp while the tools touch: the grasped tissue pulled 30 px restarts
// the cross's hold (GestureHold) and the tools' stillness, and nothing opens in 3 s more.
TEST(SciMachine, AGraspMovedWhileHeldIsStillNoCommand) {
    SciMachine m;
    m.configure(kW, kH);
    hal::Nanos t = 0;
    for (; t < 400 * kMs; t += 40 * kMs) two_tools(m, t, SciGesture::kOpenCrossing, 0, true);
    for (const hal::Nanos formed = t; t < 1600 * kMs; t += 40 * kMs)
        ASSERT_EQ(two_tools(m, t, SciGesture::kCross, ms_since(t, formed), true), "");
    for (const hal::Nanos moved = t; t <= moved + 3000 * kMs; t += 40 * kMs) {
        const double dx = std::min(30.0, ms_since(t, moved) / 4);  // 10 px a frame
        ASSERT_EQ(two_tools(m, t, SciGesture::kCross, ms_since(t, moved), true, dx), "")
            << "at " << t / kMs << " ms";
    }
    EXPECT_EQ(m.state(), SciState::kInactive);
}

TEST(SciMachine, ThreeLevelNavigationReturnAndExit) {
    Driver d;
    d.press(0, 320, 240);
    hal::Nanos t = 40 * kMs;
    auto go = [&](const std::string& label, const std::string& expect) {
        d.frame(t, 320, 240);  // off the items first
        ASSERT_EQ(d.dwell(label, t + 40 * kMs), 2000 * kMs) << label;
        EXPECT_EQ(d.menu(), expect) << label;
        t = d.t + 40 * kMs;
    };
    go("3-D effects", "3d_effects");
    go("Suture manipulation", "suture");
    go("Return", "3d_effects");
    go("Return", "main");
    go("Preoperative images", "preoperative_images");
    go("X-ray", "viewer");
    EXPECT_EQ(d.m.modality(), SciModality::kXray);
    go("Return", "preoperative_images");
    go("Return", "main");
    d.frame(t, 320, 240);
    ASSERT_EQ(d.dwell("Exit", t + 40 * kMs), 2000 * kMs);
    EXPECT_EQ(d.event(), "exit");
    EXPECT_EQ(d.m.state(), SciState::kInactive);
}

TEST(SciMachine, WheelMovesTheHighlightAndThroughImages) {
    SciParams p;
    p.image_counts = {3, 2, 1};
    Driver d(p);
    d.press(0, 320, 240);
    d.wheel(40 * kMs, +1);
    EXPECT_EQ(d.event(), "wheel");
    EXPECT_EQ(d.lit(), "Preoperative images");
    d.wheel(80 * kMs, +1);
    EXPECT_EQ(d.lit(), "Patient record");
    d.wheel(120 * kMs, -2);
    EXPECT_EQ(d.lit(), "Exit");  // wraps
    d.wheel(160 * kMs, +1);
    EXPECT_EQ(d.lit(), "Preoperative images");
    // The wheel's highlight does not dwell-click; the button clicks it.
    for (int k = 5; k < 100; ++k) d.frame(k * 40 * kMs, 320, 240);
    EXPECT_EQ(d.menu(), "main");
    d.press(4000 * kMs, 320, 240);
    EXPECT_EQ(d.event(), "click");
    EXPECT_EQ(d.menu(), "preoperative_images");
    d.wheel(4040 * kMs, +1);
    d.press(4080 * kMs, 320, 240);
    EXPECT_EQ(d.menu(), "viewer");
    EXPECT_EQ(d.m.image_index(), 0);
    d.wheel(4120 * kMs, +1);
    EXPECT_EQ(d.event(), "image");
    EXPECT_EQ(d.m.image_index(), 1);
    d.wheel(4160 * kMs, +4);
    EXPECT_EQ(d.m.image_index(), 2);  // (1 + 4) mod 3
    d.wheel(4200 * kMs, -3);
    EXPECT_EQ(d.m.image_index(), 2);
}

TEST(SciMachine, LongPressDeactivates) {
    Driver d;
    d.press(0, 320, 240);
    d.frame(800 * kMs, 320, 240, SciGesture::kNone, 0, false,
            {{hal::ControlEvent::Kind::kLongPress, 0, 0, 0}});
    EXPECT_EQ(d.event(), "deactivate");
    EXPECT_EQ(d.m.state(), SciState::kInactive);
}

TEST(SciMachine, RingLayoutPreviousNextMainMenu) {
    SciParams p;
    p.layout = SciLayout::kRing;
    p.image_counts = {3, 0, 0};
    Driver d(p);
    d.press(0, 320, 240);
    ASSERT_EQ(d.m.menu().count, 4u);
    EXPECT_EQ(d.m.menu().hit(320, 240 - 0.35f * kH), 0);  // top of the ring: CT
    EXPECT_EQ(d.m.menu().hit(320 - 0.35f * kH, 240), 3);  // left: EXIT
    EXPECT_EQ(d.m.menu().hit(320, 240), -1);              // the view stays free
    EXPECT_EQ(d.dwell("CT", 40 * kMs), 2000 * kMs);
    EXPECT_EQ(d.menu(), "viewer");
    d.frame(d.t + 40 * kMs, 320, 240);
    EXPECT_EQ(d.dwell("Next", d.t + 40 * kMs), 2000 * kMs);
    EXPECT_EQ(d.m.image_index(), 1);
    d.frame(d.t + 40 * kMs, 320, 240);
    EXPECT_EQ(d.dwell("Previous", d.t + 40 * kMs), 2000 * kMs);
    d.frame(d.t + 40 * kMs, 320, 240);
    EXPECT_EQ(d.dwell("Previous", d.t + 40 * kMs), 2000 * kMs);
    EXPECT_EQ(d.m.image_index(), 2);
    d.frame(d.t + 40 * kMs, 320, 240);
    EXPECT_EQ(d.dwell("Main menu", d.t + 40 * kMs), 2000 * kMs);
    EXPECT_EQ(d.menu(), "main");
}

TEST(SciScene, ThreeLevelMainMenuItemsAtTheirPlaces) {
    Driver d;
    d.press(0, 320, 240);
    const auto [x, y] = d.at("Patient record");
    d.frame(40 * kMs, x, y);
    d.frame(1040 * kMs, x, y);
    hal::OverlayScene s;
    SciSceneInput in;
    in.width = kW, in.height = kH, in.has_tip = true, in.tip_x = static_cast<float>(x),
    in.tip_y = static_cast<float>(y);
    build_sci_scene(d.m, SciParams{}, in, s);
    ASSERT_EQ(s.quads.count, 4u);
    ASSERT_EQ(s.texts.count, 4u);
    EXPECT_FLOAT_EQ(s.quads.items[1].x, 0.03f * kW);
    EXPECT_FLOAT_EQ(s.quads.items[1].y, 0.10f * kH + 0.12f * kH);
    EXPECT_FLOAT_EQ(s.quads.items[1].width, 0.26f * kW);
    EXPECT_EQ(s.quads.items[1].fill, (hal::Rgba8{250, 190, 40, 190}));  // highlighted
    EXPECT_EQ(s.quads.items[0].fill, (hal::Rgba8{30, 60, 110, 130}));
    EXPECT_STREQ(s.texts.items[1].utf8.data(), "Patient record");
    ASSERT_EQ(s.discs.count, 1u);  // the dwell arc, half way
    EXPECT_FLOAT_EQ(s.discs.items[0].sweep_deg, 180.0f);
    EXPECT_FLOAT_EQ(s.discs.items[0].cx, static_cast<float>(x));
    // Inactive: nothing at all.
    Driver off;
    off.frame(0, 320, 240);
    build_sci_scene(off.m, SciParams{}, in, s);
    EXPECT_TRUE(s.empty());
}

}  // namespace
}  // namespace endotower::sci
