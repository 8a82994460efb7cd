// GpioButton against the kernel's gpio-sim (built by setup.sh) in the qemu guest:
// a 4-line chip labelled "endotower-button" made through configfs; the test moves
// line levels with the sim's pull attribute, bouncing, and checks the debounced
// press / long-press / release events and their kernel timestamps.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <time.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "endotower/gpio/gpio_button.hpp"

namespace endotower::gpio {
namespace {

using Kind = hal::ControlEvent::Kind;
constexpr hal::Nanos ms = hal::kMillisecond;
const std::string kCfg = "/sys/kernel/config/gpio-sim/endotower";

hal::Nanos now_ns() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * hal::kSecond + ts.tv_nsec;
}

bool write_file(const std::string& path, const std::string& value) {
    std::ofstream f(path);
    f << value;
    f.flush();
    return static_cast<bool>(f);
}

std::string read_word(const std::string& path) {
    std::ifstream f(path);
    std::string s;
    f >> s;
    return s;
}

class GpioGuest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        ::mkdir(kCfg.c_str(), 0755);
        ::mkdir((kCfg + "/gpio-bank0").c_str(), 0755);
        ASSERT_TRUE(write_file(kCfg + "/gpio-bank0/num_lines", "4"));
        ASSERT_TRUE(write_file(kCfg + "/gpio-bank0/label", "endotower-button"));
        ASSERT_TRUE(write_file(kCfg + "/live", "1"));
        chip_ = read_word(kCfg + "/gpio-bank0/chip_name");
        dev_ = read_word(kCfg + "/dev_name");
        ASSERT_FALSE(chip_.empty());
    }
    // Sets the level the sim drives on `line` (its pull).
    static void level(int line, bool high) {
        ASSERT_TRUE(write_file("/sys/devices/platform/" + dev_ + "/" + chip_ + "/sim_gpio" +
                                   std::to_string(line) + "/pull",
                               high ? "pull-up" : "pull-down"));
    }
    static std::vector<hal::ControlEvent> collect(GpioButton& b) {
        std::vector<hal::ControlEvent> out;
        hal::ControlEvent e;
        while (b.poll(e)) out.push_back(e);
        return out;
    }
    static void sleep_ms(int n) { std::this_thread::sleep_for(std::chrono::milliseconds(n)); }
    static inline std::string chip_, dev_;
};

TEST_F(GpioGuest, BouncyPressLongPressAndReleaseWithKernelTimestamps) {
    level(0, false);
    GpioButtonConfig c;
    c.chip = "endotower-button";  // found by label
    c.line = 0;
    c.debounce = {50 * ms, 400 * ms, 0};
    GpioButton button(c);
    std::string error;
    ASSERT_TRUE(button.start(error)) << error;

    const hal::Nanos t0 = now_ns();
    for (bool high : {true, false, true, false, true}) level(0, high);  // contact bounce
    const hal::Nanos t1 = now_ns();
    sleep_ms(700);  // past the debounce and the long-press time
    auto ev = collect(button);
    ASSERT_EQ(ev.size(), 2u);
    EXPECT_EQ(ev[0].kind, Kind::kButtonPress);
    EXPECT_GE(ev[0].time_ns, t0);  // the first edge's kernel timestamp (CLOCK_MONOTONIC)
    EXPECT_LE(ev[0].time_ns, t1);
    EXPECT_EQ(ev[1].kind, Kind::kLongPress);
    EXPECT_EQ(ev[1].time_ns, ev[0].time_ns + 400 * ms);

    const hal::Nanos t2 = now_ns();
    for (bool high : {false, true, false}) level(0, high);
    const hal::Nanos t3 = now_ns();
    sleep_ms(300);
    ev = collect(button);
    ASSERT_EQ(ev.size(), 1u);
    EXPECT_EQ(ev[0].kind, Kind::kButtonRelease);
    EXPECT_GE(ev[0].time_ns, t2);
    EXPECT_LE(ev[0].time_ns, t3);
    const GpioStats s = button.stats();
    EXPECT_GE(s.edges, 2u);  // irq_sim may merge edges written back to back
    EXPECT_EQ(s.events, 3u);
    EXPECT_EQ(s.dropped, 0u);
}

TEST_F(GpioGuest, ActiveLowGlitchIgnoredThenPress) {
    level(1, true);  // idle high: not pressed on an active-low line
    GpioButtonConfig c;
    c.chip = chip_;  // found by name
    c.line = 1;
    c.active_low = true;
    c.debounce = {100 * ms, 0, 3};
    GpioButton button(c);
    std::string error;
    ASSERT_TRUE(button.start(error)) << error;
    level(1, false);
    level(1, true);  // a pulse of microseconds
    sleep_ms(300);
    EXPECT_TRUE(collect(button).empty());
    EXPECT_LE(button.stats().glitches, 1u);

    const hal::Nanos t0 = now_ns();
    level(1, false);  // pressed
    sleep_ms(300);
    level(1, true);
    sleep_ms(300);
    const auto ev = collect(button);
    ASSERT_EQ(ev.size(), 2u);
    EXPECT_EQ(ev[0].kind, Kind::kButtonPress);
    EXPECT_EQ(ev[0].button, 3);
    EXPECT_GE(ev[0].time_ns, t0);
    EXPECT_EQ(ev[1].kind, Kind::kButtonRelease);
    EXPECT_GE(ev[1].time_ns - ev[0].time_ns, 300 * ms);  // kernel timestamps, not our wake-ups
}

TEST_F(GpioGuest, ClearErrorsForWrongChipLineOrBusyLine) {
    std::string error;
    GpioButton wrong_chip({"no-such-chip", 0, false, {}, "endotower"});
    EXPECT_FALSE(wrong_chip.start(error));
    EXPECT_EQ(error.rfind("gpiod_chip_open_lookup(no-such-chip):", 0), 0u) << error;
    EXPECT_NE(error.find("check button.chip"), std::string::npos) << error;

    GpioButton wrong_line({"endotower-button", 9, false, {}, "endotower"});
    EXPECT_FALSE(wrong_line.start(error));
    EXPECT_NE(error.find("GPIO endotower-button line 9"), std::string::npos) << error;
    EXPECT_NE(error.find("(the chip has 4 lines)"), std::string::npos) << error;

    GpioButton first({"endotower-button", 2, false, {}, "endotower"});
    ASSERT_TRUE(first.start(error)) << error;
    GpioButton second({"endotower-button", 2, false, {}, "endotower"});
    EXPECT_FALSE(second.start(error));
    EXPECT_NE(error.find("Device or resource busy"), std::string::npos) << error;
    EXPECT_NE(error.find("used by another consumer"), std::string::npos) << error;
}

}  // namespace
}  // namespace endotower::gpio
