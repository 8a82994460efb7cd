#include "endotower/usb/usb_hotplug.hpp"

#include <libusb.h>

#include <atomic>
#include <cstdio>
#include <thread>

namespace endotower::usb {

struct UsbHotplug::Impl {
    std::uint16_t vid = 0, pid = 0;
    libusb_context* ctx = nullptr;
    libusb_hotplug_callback_handle handle = 0;
    bool registered = false;
    Listener listener;
    std::thread thread;
    std::atomic<bool> stopping{false};
    std::atomic<std::uint64_t> arrivals{0}, removals{0};

    std::string name() const {
        char b[32];
        std::snprintf(b, sizeof b, "USB %04x:%04x", vid, pid);
        return b;
    }

    static int on_event(libusb_context*, libusb_device*, libusb_hotplug_event event, void* user) {
        auto* m = static_cast<Impl*>(user);
        const bool arrived = event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED;
        (arrived ? m->arrivals : m->removals).fetch_add(1);
        if (m->listener) m->listener(arrived);
        return 0;  // stay registered
    }

    void close() {
        if (registered) libusb_hotplug_deregister_callback(ctx, handle);
        registered = false;
        if (ctx != nullptr) libusb_exit(ctx);
        ctx = nullptr;
    }
};

UsbHotplug::UsbHotplug(std::uint16_t vid, std::uint16_t pid) : impl_(std::make_unique<Impl>()) {
    impl_->vid = vid;
    impl_->pid = pid;
}

UsbHotplug::~UsbHotplug() {
    stop();
}

bool UsbHotplug::start(Listener listener, std::string& error) {
    Impl& m = *impl_;
    if (m.thread.joinable()) return true;
    if (const int r = libusb_init(&m.ctx); r != 0) {
        m.ctx = nullptr;
        error = m.name() + ": libusb_init: " + libusb_strerror(r);
        return false;
    }
    if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
        error = m.name() +
                ": libusb has no hotplug support on this system (LIBUSB_CAP_HAS_HOTPLUG); "
                "the handle reconnects through its /dev/hidraw watch only";
        m.close();
        return false;
    }
    m.listener = std::move(listener);
    const int r = libusb_hotplug_register_callback(
        m.ctx, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT,
        LIBUSB_HOTPLUG_ENUMERATE, m.vid, m.pid, LIBUSB_HOTPLUG_MATCH_ANY, &Impl::on_event, &m,
        &m.handle);
    if (r != LIBUSB_SUCCESS) {
        error = m.name() + ": libusb_hotplug_register_callback: " + libusb_strerror(r);
        m.close();
        return false;
    }
    m.registered = true;
    m.stopping = false;
    m.thread = std::thread([&m] {
        while (!m.stopping) {
            // Blocks until an event (or libusb_interrupt_event_handler from stop()).
            libusb_handle_events_completed(m.ctx, nullptr);
        }
    });
    return true;
}

void UsbHotplug::stop() {
    Impl& m = *impl_;
    if (!m.thread.joinable()) return;
    m.stopping = true;
    libusb_interrupt_event_handler(m.ctx);
    m.thread.join();
    m.close();
}

std::uint64_t UsbHotplug::arrivals() const {
    return impl_->arrivals;
}
std::uint64_t UsbHotplug::removals() const {
    return impl_->removals;
}

}  // namespace endotower::usb
