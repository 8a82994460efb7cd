#include "endotower/sim/virtual_clock.hpp"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace endotower::sim {
namespace {

TEST(VirtualClock, StartsWhereToldAndIsVirtual) {
    VirtualClock a;
    EXPECT_EQ(a.now(), 0);
    VirtualClock b(123'456'789);
    EXPECT_EQ(b.now(), 123'456'789);
    EXPECT_TRUE(b.is_virtual());
}

TEST(VirtualClock, SleepUntilJumpsForwardAtOnce) {
    VirtualClock c(1'000);
    c.sleep_until(5 * hal::kSecond);
    EXPECT_EQ(c.now(), 5 * hal::kSecond);
    c.sleep_until(5 * hal::kSecond);  // the same time again: no change
    EXPECT_EQ(c.now(), 5 * hal::kSecond);
}

TEST(VirtualClock, NeverGoesBack) {
    VirtualClock c(10 * hal::kMillisecond);
    c.sleep_until(3 * hal::kMillisecond);
    EXPECT_EQ(c.now(), 10 * hal::kMillisecond);
    c.advance(-5);
    EXPECT_EQ(c.now(), 10 * hal::kMillisecond);
    c.advance(0);
    EXPECT_EQ(c.now(), 10 * hal::kMillisecond);
}

TEST(VirtualClock, AdvanceAddsToNow) {
    VirtualClock c(7);
    c.advance(40 * hal::kMillisecond);
    EXPECT_EQ(c.now(), 7 + 40 * hal::kMillisecond);
    c.advance(1);
    EXPECT_EQ(c.now(), 8 + 40 * hal::kMillisecond);
}

TEST(VirtualClock, ConcurrentSleepersEndAtTheLatestTarget) {
    VirtualClock c;
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t) {
        threads.emplace_back([&c, t] {
            for (hal::Nanos i = 0; i < 10'000; ++i) c.sleep_until(i * 4 + t);
        });
    }
    for (auto& th : threads) th.join();
    EXPECT_EQ(c.now(), 9'999 * 4 + 3);
}

}  // namespace
}  // namespace endotower::sim
