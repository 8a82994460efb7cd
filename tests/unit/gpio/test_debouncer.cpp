// The button debouncer's state machine, fed edge sequences with known timestamps.
#include <gtest/gtest.h>

#include <vector>

#include "endotower/gpio/debouncer.hpp"

namespace endotower::gpio {
namespace {

using Kind = hal::ControlEvent::Kind;
constexpr hal::Nanos ms = hal::kMillisecond;

std::vector<hal::ControlEvent> drain(ButtonDebouncer& d, hal::Nanos now) {
    std::vector<hal::ControlEvent> out;
    hal::ControlEvent e;
    while (d.next(now, e)) out.push_back(e);
    return out;
}

TEST(Debouncer, BouncyPressAndReleaseGiveOneEventEachAtTheFirstEdge) {
    ButtonDebouncer d({20 * ms, 0, 0}, false);
    for (hal::Nanos t : {100, 101, 103, 104, 108})
        d.edge(t % 2 == 0, t * ms);  // ends active at 108
    EXPECT_EQ(d.deadline(), 128 * ms);
    EXPECT_TRUE(drain(d, 127 * ms).empty());  // not yet stable for 20 ms
    auto ev = drain(d, 128 * ms);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].kind, Kind::kButtonPress);
    EXPECT_EQ(ev[0].time_ns, 100 * ms);
    EXPECT_TRUE(d.pressed());
    EXPECT_EQ(d.deadline(), -1);  // no long press configured
    d.edge(false, 300 * ms);      // contact breaks at 300, bounces, inactive from 305
    d.edge(true, 302 * ms);
    d.edge(false, 305 * ms);
    ev = drain(d, 400 * ms);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].kind, Kind::kButtonRelease);
    EXPECT_EQ(ev[0].time_ns, 300 * ms);
    EXPECT_EQ(d.glitches(), 0u);
}

TEST(Debouncer, GlitchShorterThanDebounceIsIgnoredAndCounted) {
    ButtonDebouncer d({20 * ms, 0, 0}, false);
    d.edge(true, 10 * ms);
    d.edge(false, 25 * ms);  // 15 ms pulse
    EXPECT_TRUE(drain(d, 100 * ms).empty());
    EXPECT_EQ(d.glitches(), 1u);
    EXPECT_FALSE(d.pressed());
    d.edge(true, 200 * ms);  // a press exactly the debounce time long counts
    d.edge(false, 220 * ms);
    auto ev = drain(d, 219 * ms);
    EXPECT_TRUE(ev.empty());
}

TEST(Debouncer, PressExactlyDebounceLongCounts) {
    ButtonDebouncer d({20 * ms, 0, 0}, false);
    d.edge(true, 200 * ms);
    auto ev = drain(d, 220 * ms);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].kind, Kind::kButtonPress);
}

TEST(Debouncer, LongPressAtPressPlusLongTimeBeforeTheRelease) {
    ButtonDebouncer d({20 * ms, 800 * ms, 2}, false);
    d.edge(true, 1000 * ms);
    auto ev = drain(d, 1020 * ms);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].button, 2);
    EXPECT_EQ(d.deadline(), 1800 * ms);
    EXPECT_TRUE(drain(d, 1799 * ms).empty());
    // Released at 1900, decided at 1920; the long press (1800) comes first.
    d.edge(false, 1900 * ms);
    ev = drain(d, 1950 * ms);
    ASSERT_EQ(ev.size(), 2u);
    EXPECT_EQ(ev[0].kind, Kind::kLongPress);
    EXPECT_EQ(ev[0].time_ns, 1800 * ms);
    EXPECT_EQ(ev[1].kind, Kind::kButtonRelease);
    EXPECT_EQ(ev[1].time_ns, 1900 * ms);
}

TEST(Debouncer, ReleaseBeforeLongTimeMeansNoLongPress) {
    ButtonDebouncer d({20 * ms, 800 * ms, 0}, false);
    d.edge(true, 0);
    ASSERT_EQ(drain(d, 20 * ms).size(), 1u);
    d.edge(false, 790 * ms);
    // Asked late (after the long-press time): the release at 790 wins.
    const auto ev = drain(d, 2000 * ms);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].kind, Kind::kButtonRelease);
    EXPECT_EQ(ev[0].time_ns, 790 * ms);
}

TEST(Debouncer, GlitchDuringHoldDoesNotCancelTheLongPress) {
    ButtonDebouncer d({20 * ms, 800 * ms, 0}, false);
    d.edge(true, 0);
    ASSERT_EQ(drain(d, 20 * ms).size(), 1u);
    d.edge(false, 790 * ms);
    d.edge(true, 795 * ms);
    EXPECT_EQ(d.deadline(), 815 * ms);  // the excursion must resolve first
    EXPECT_TRUE(drain(d, 810 * ms).empty());
    const auto ev = drain(d, 815 * ms);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].kind, Kind::kLongPress);
    EXPECT_EQ(ev[0].time_ns, 800 * ms);
    EXPECT_EQ(d.glitches(), 1u);
}

TEST(Debouncer, HeldAtStartGivesNoEventsUntilReleased) {
    ButtonDebouncer d({20 * ms, 800 * ms, 0}, true);
    EXPECT_TRUE(d.pressed());
    EXPECT_EQ(d.deadline(), -1);
    EXPECT_TRUE(drain(d, 5000 * ms).empty());
    d.edge(false, 6000 * ms);
    const auto ev = drain(d, 6020 * ms);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].kind, Kind::kButtonRelease);
}

TEST(Debouncer, RepeatedSameLevelEdgesKeepTheFirstTimestamp) {
    // The v1 uAPI reads the level when it reports, so two "rising" events can follow.
    ButtonDebouncer d({20 * ms, 0, 0}, false);
    d.edge(true, 50 * ms);
    d.edge(true, 55 * ms);
    EXPECT_TRUE(drain(d, 74 * ms).empty());
    const auto ev = drain(d, 75 * ms);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].time_ns, 50 * ms);
}

}  // namespace
}  // namespace endotower::gpio
