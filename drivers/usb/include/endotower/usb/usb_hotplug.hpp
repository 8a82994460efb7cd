// UsbHotplug: libusb hotplug notifications (arrival, removal) for one VID/PID, on
// a thread that sleeps in libusb_handle_events until the kernel reports a change:
// no polling loop. The firmware connects it to HidHandle::notify_arrival so a
// replugged handle is opened at once. Devices already present when start() runs
// are reported as arrivals (LIBUSB_HOTPLUG_ENUMERATE).
//
// start() fails clearly when libusb has no hotplug support here
// (LIBUSB_CAP_HAS_HOTPLUG); the handle then still reconnects through its own
// /dev/hidraw* watch. libusb's udev backend needs udevd running to see events.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace endotower::usb {

class UsbHotplug {
public:
    // Called on the hotplug thread; must not block. arrived = false on removal.
    using Listener = std::function<void(bool arrived)>;

    UsbHotplug(std::uint16_t vid, std::uint16_t pid);
    ~UsbHotplug();  // stops the thread

    // libusb_init, the callback registration and the thread. False with `error`.
    bool start(Listener listener, std::string& error);
    void stop();

    std::uint64_t arrivals() const;
    std::uint64_t removals() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::usb
