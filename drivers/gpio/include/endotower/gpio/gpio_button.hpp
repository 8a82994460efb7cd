// GpioButton: a push button on a GPIO line as a ControlInput, through libgpiod 1.6.
// The line is requested for both edges (active-low handled by the kernel, so events
// and levels are logical: true = pressed); the kernel's edge timestamps
// (CLOCK_MONOTONIC since Linux 5.7) feed a ButtonDebouncer (debouncer.hpp). A reader
// thread sleeps in poll() on the line's event fd until an edge or the debouncer's
// next deadline, and queues decided events in a fixed ring; poll() only pops it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "endotower/gpio/debouncer.hpp"
#include "endotower/hal/control_input.hpp"

namespace endotower::gpio {

struct GpioButtonConfig {
    std::string chip;         // gpiochip name, /dev path, label or number (gpiod_chip_open_lookup)
    unsigned line = 0;        // offset on that chip
    bool active_low = false;  // true: pressed pulls the line low
    DebounceParams debounce;  // 20 ms debounce, 800 ms long press by default
    std::string consumer = "endotower";  // shown by gpioinfo
};

struct GpioStats {
    std::uint64_t edges = 0;     // kernel edge events read
    std::uint64_t events = 0;    // press/release/long-press queued
    std::uint64_t glitches = 0;  // excursions shorter than the debounce time
    std::uint64_t dropped = 0;   // ring full
};

class GpioButton final : public hal::ControlInput {
public:
    explicit GpioButton(GpioButtonConfig config);
    ~GpioButton() override;

    // Opens the chip, requests the line, reads its level and starts the thread.
    // False with `error` naming the chip and line (and the errno) on failure.
    bool start(std::string& error);
    void stop();

    bool poll(hal::ControlEvent& out) override;  // never blocks, never allocates
    GpioStats stats() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::gpio
