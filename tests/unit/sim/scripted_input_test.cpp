#include "endotower/sim/scripted_input.hpp"

#include <gtest/gtest.h>

#include "endotower/sim/virtual_clock.hpp"

namespace endotower::sim {
namespace {

using Kind = hal::ControlEvent::Kind;
constexpr hal::Nanos kStart = 5 * hal::kSecond;
constexpr double kFps = 25.0;
constexpr hal::Nanos kPeriod = 40 * hal::kMillisecond;  // 1 / kFps

Timeline parse(const std::string& text) {
    Timeline tl;
    std::string error;
    EXPECT_TRUE(parse_timeline(text, "test", tl, error)) << error;
    return tl;
}

TEST(ScriptedInput, HandsOutEventsInTimeOrderAsTheClockReachesThem) {
    // File order differs from time order; frame 25 and t 1.0 are the same instant.
    const Timeline tl = parse(
        "frame 25 release\n"  // 5.000 + 1.000
        "t 0.5 wheel +3\n"    // 5.500
        "frame 0 press 2\n"   // 5.000
        "t 1.0 press 1\n"     // 6.000, after frame 25 in file order
        "t 0.5 wheel -1\n");  // 5.500, after the first wheel in file order
    VirtualClock clock(kStart - 1);
    ScriptedInput input(tl, clock, kStart, kFps);
    EXPECT_EQ(input.remaining(), 5u);

    hal::ControlEvent ev;
    EXPECT_FALSE(input.poll(ev));  // nothing is due before the first frame

    clock.sleep_until(kStart);
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.kind, Kind::kButtonPress);
    EXPECT_EQ(ev.button, 2);
    EXPECT_EQ(ev.time_ns, kStart);
    EXPECT_FALSE(input.poll(ev));

    clock.sleep_until(kStart + 499'999'999);
    EXPECT_FALSE(input.poll(ev));
    clock.sleep_until(kStart + 500'000'000);
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.kind, Kind::kWheel);
    EXPECT_EQ(ev.delta, 3);
    EXPECT_EQ(ev.time_ns, kStart + 500'000'000);
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.kind, Kind::kWheel);
    EXPECT_EQ(ev.delta, -1);
    EXPECT_EQ(ev.time_ns, kStart + 500'000'000);
    EXPECT_FALSE(input.poll(ev));
    EXPECT_EQ(input.remaining(), 2u);

    // Far past both: they still come one per poll, in order.
    clock.sleep_until(kStart + 10 * hal::kSecond);
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.kind, Kind::kButtonRelease);
    EXPECT_EQ(ev.button, 0);
    EXPECT_EQ(ev.time_ns, kStart + 25 * kPeriod);
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.kind, Kind::kButtonPress);
    EXPECT_EQ(ev.button, 1);
    EXPECT_EQ(ev.time_ns, kStart + hal::kSecond);
    EXPECT_FALSE(input.poll(ev));
    EXPECT_EQ(input.remaining(), 0u);
}

TEST(ScriptedInput, FrameAnchorsFireExactlyAtTheFramesCaptureTime) {
    // 30 fps: frame n is captured at llround(n * 1e9 / 30) (RecordedFrameSource), not
    // at n * 33'333'333, which would put "frame 60" 20 ns before 2.0 s.
    const Timeline tl = parse("frame 3 press\nframe 1 release\nframe 60 wheel 1\n");
    VirtualClock clock;
    ScriptedInput input(tl, clock, 100, 30.0);
    hal::ControlEvent ev;
    clock.sleep_until(100 + 33'333'333);
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.kind, Kind::kButtonRelease);
    EXPECT_EQ(ev.time_ns, 100 + 33'333'333);
    clock.sleep_until(100 + 100'000'000 - 1);
    EXPECT_FALSE(input.poll(ev));
    clock.advance(1);
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.kind, Kind::kButtonPress);
    EXPECT_EQ(ev.time_ns, 100 + 100'000'000);
    clock.sleep_until(100 + 2 * hal::kSecond);
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.time_ns, 100 + 2 * hal::kSecond);
}

TEST(ScriptedInput, EmptyTimelineNeverFires) {
    VirtualClock clock;
    ScriptedInput input(Timeline{}, clock, 0, kFps);
    clock.sleep_until(hal::kSecond * 1000);
    hal::ControlEvent ev;
    EXPECT_FALSE(input.poll(ev));
    EXPECT_EQ(input.remaining(), 0u);
}

TEST(ScriptedInput, AbsurdFrameIndexDoesNotOverflowIntoThePast) {
    const Timeline tl = parse("frame 9000000000000000000 press\nframe 1 release\n");
    VirtualClock clock;
    ScriptedInput input(tl, clock, kStart, kFps);
    clock.sleep_until(kStart + 1000 * hal::kSecond);
    hal::ControlEvent ev;
    ASSERT_TRUE(input.poll(ev));
    EXPECT_EQ(ev.kind, Kind::kButtonRelease);
    EXPECT_FALSE(input.poll(ev));
    EXPECT_EQ(input.remaining(), 1u);
}

}  // namespace
}  // namespace endotower::sim
