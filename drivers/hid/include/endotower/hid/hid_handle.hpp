// HidHandle: the tool handle as a ControlInput, through hidapi 0.13 (hidraw backend).
// The device is chosen by VID/PID (+ serial, usage page when given); its buttons and
// wheel come from its report descriptor (report_descriptor.hpp), read from sysfs.
// A reader thread reads reports, stamps them with CLOCK_MONOTONIC at read time,
// decodes them and queues the events in a fixed ring; poll() only pops that ring.
// Unplug: the held buttons are released (events), the device is closed, and the
// thread sleeps until an arrival: a new /dev/hidraw* node (inotify, any bus) or
// notify_arrival() (drivers/usb hotplug). No polling loop while absent.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "endotower/hal/control_input.hpp"

namespace endotower::hid {

struct HidHandleConfig {
    std::uint16_t vid = 0;
    std::uint16_t pid = 0;
    std::string serial;            // empty = any
    std::uint16_t usage_page = 0;  // top-level usage page; 0 = any
};

struct HidStats {
    std::uint64_t reports = 0;   // accepted input reports
    std::uint64_t rejected = 0;  // short + oversized + unknown ID + empty
    std::uint64_t short_reports = 0, oversized = 0, unknown_id = 0;
    std::uint64_t dropped = 0;   // events lost because the ring was full
    std::uint64_t connects = 0;  // successful opens (1 + reconnects)
    std::uint64_t disconnects = 0;
};

class HidHandle final : public hal::ControlInput {
public:
    explicit HidHandle(HidHandleConfig config);
    ~HidHandle() override;  // stops the thread

    // hid_init, inotify on /dev, the reader thread; opens the device if present.
    // False (with `error`) only when those fail; an absent device is not an error
    // (connected() says, last_error() says why).
    bool start(std::string& error);
    void stop();

    bool poll(hal::ControlEvent& out) override;  // never blocks, never allocates
    // Any thread (e.g. the USB hotplug callback): look for the device now.
    void notify_arrival();

    bool connected() const;
    HidStats stats() const;
    std::string last_error() const;  // e.g. "HID 1234:5678: not found"; not per frame

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::hid
