#include "endotower/hid/hid_handle.hpp"

#include <hidapi/hidapi.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/inotify.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <thread>
#include <vector>

#include "endotower/hid/report_descriptor.hpp"
#include "endotower/system/monotonic_clock.hpp"
#include "endotower/system/spsc_ring.hpp"
#include "endotower/system/syscall.hpp"

namespace endotower::hid {

namespace {
constexpr int kReadTimeoutMs = 250;  // how soon stop() is noticed while connected

std::string hex_id(std::uint16_t vid, std::uint16_t pid) {
    char b[16];
    std::snprintf(b, sizeof b, "%04x:%04x", vid, pid);
    return b;
}

// hidapi's hidraw path is /dev/hidrawN; the kernel exposes the descriptor in sysfs.
bool read_descriptor(const std::string& dev_path, std::vector<std::uint8_t>& out) {
    const auto slash = dev_path.rfind('/');
    const std::string node = dev_path.substr(slash == std::string::npos ? 0 : slash + 1);
    std::ifstream in("/sys/class/hidraw/" + node + "/device/report_descriptor", std::ios::binary);
    if (!in) return false;
    out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return !out.empty();
}
}  // namespace

struct HidHandle::Impl {
    HidHandleConfig config;
    std::string name;  // "HID vvvv:pppp" for messages
    system::MonotonicClock clock;
    system::SpscRing<hal::ControlEvent, 256> ring;
    std::thread thread;
    int wake_fd = -1, inotify_fd = -1;
    std::atomic<bool> stopping{false}, is_connected{false};
    hid_device* dev = nullptr;
    HandleLayout layout;
    std::unique_ptr<ReportDecoder> decoder;
    mutable std::mutex stats_mutex;  // guards stats and error (not on the poll() path)
    HidStats stats;
    std::string error;

    void set_error(std::string e) {
        std::lock_guard lock(stats_mutex);
        error = std::move(e);
    }
    void push(const hal::ControlEvent& e) {
        if (!ring.push(e)) {
            std::lock_guard lock(stats_mutex);
            ++stats.dropped;
        }
    }

    bool matches(const hid_device_info* d) const {
        if (config.usage_page != 0 && d->usage_page != config.usage_page) return false;
        if (config.serial.empty()) return true;
        if (d->serial_number == nullptr) return false;
        std::wstring want(config.serial.begin(), config.serial.end());
        return want == d->serial_number;
    }

    bool try_open() {
        hid_device_info* list = hid_enumerate(config.vid, config.pid);
        std::string why =
            name + ": no device with this VID/PID" +
            (config.serial.empty() ? "" : " and serial " + config.serial) +
            (config.usage_page ? " and usage page " + hex_id(config.usage_page, 0).substr(0, 4)
                               : "");
        for (hid_device_info* d = list; d != nullptr && dev == nullptr; d = d->next) {
            if (!matches(d)) continue;
            std::vector<std::uint8_t> desc;
            HandleLayout l;
            std::string perr;
            if (!read_descriptor(d->path, desc)) {
                why = name + " (" + d->path + "): cannot read its report descriptor from sysfs";
                continue;
            }
            if (!parse_report_descriptor(desc, l, perr)) {
                why = name + " (" + d->path + "): " + perr;
                continue;
            }
            dev = hid_open_path(d->path);
            if (dev == nullptr) {
                why = name + " (" + d->path +
                      "): cannot open (permissions? the udev rule gives the group access)";
                continue;
            }
            layout = l;
            decoder = std::make_unique<ReportDecoder>(layout);
        }
        hid_free_enumeration(list);
        if (dev == nullptr) {
            set_error(why);
            return false;
        }
        {
            std::lock_guard lock(stats_mutex);
            ++stats.connects;
            error.clear();
        }
        is_connected = true;
        return true;
    }

    void close_device() {
        hid_close(dev);
        dev = nullptr;
        is_connected = false;
        std::lock_guard lock(stats_mutex);
        ++stats.disconnects;
        error = name + ": device gone (unplugged); waiting for it to come back";
    }

    // Sleeps until stop, notify_arrival() or a new/changed /dev/hidraw* node.
    void wait_for_arrival() {
        pollfd fds[2] = {{wake_fd, POLLIN, 0}, {inotify_fd, POLLIN, 0}};
        if (system::retry_eintr([&] { return ::poll(fds, inotify_fd >= 0 ? 2 : 1, -1); }) < 0)
            return;
        if (fds[0].revents & POLLIN) {
            std::uint64_t v;
            (void)!::read(wake_fd, &v, sizeof v);
        }
        if (inotify_fd >= 0 && (fds[1].revents & POLLIN)) {
            alignas(inotify_event) char buf[4096];
            (void)!::read(inotify_fd, buf,
                          sizeof buf);  // which node does not matter: enumerate again
        }
    }

    void run() {
        std::array<std::uint8_t, kMaxReportBytes + 2> buf{};  // +1 ID, +1 to see oversized reports
        std::array<hal::ControlEvent, kMaxButtons + 1> events{};
        while (!stopping) {
            if (dev == nullptr) {
                if (!try_open()) wait_for_arrival();
                continue;
            }
            const int n = hid_read_timeout(dev, buf.data(), buf.size(), kReadTimeoutMs);
            if (n < 0) {
                release_all();
                close_device();
                continue;
            }
            if (n == 0) continue;
            int count = 0;
            const ReportStatus s = decoder->decode({buf.data(), static_cast<std::size_t>(n)},
                                                   clock.now(), events, count);
            {
                std::lock_guard lock(stats_mutex);
                switch (s) {
                    case ReportStatus::kOk:
                        ++stats.reports;
                        break;
                    case ReportStatus::kShort:
                        ++stats.short_reports, ++stats.rejected;
                        break;
                    case ReportStatus::kOversized:
                        ++stats.oversized, ++stats.rejected;
                        break;
                    case ReportStatus::kUnknownId:
                        ++stats.unknown_id, ++stats.rejected;
                        break;
                    case ReportStatus::kEmpty:
                        ++stats.rejected;
                        break;
                }
            }
            for (int i = 0; i < count; ++i) push(events[i]);
        }
    }

    // Buttons held at unplug are released, so the pipeline never sees a stuck press.
    void release_all() {
        std::array<hal::ControlEvent, kMaxButtons + 1> events{};
        const int count = decoder->release_all(clock.now(), events);
        for (int i = 0; i < count; ++i) push(events[i]);
    }
};

HidHandle::HidHandle(HidHandleConfig config) : impl_(std::make_unique<Impl>()) {
    impl_->config = std::move(config);
    impl_->name = "HID " + hex_id(impl_->config.vid, impl_->config.pid);
}

HidHandle::~HidHandle() {
    stop();
}

bool HidHandle::start(std::string& error) {
    Impl& m = *impl_;
    if (m.thread.joinable()) return true;
    if (hid_init() != 0) {
        error = m.name + ": hid_init failed";
        return false;
    }
    m.wake_fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (m.wake_fd < 0) {
        error = m.name + ": " + system::errno_message("eventfd", "wake", errno);
        return false;
    }
    // Without inotify the handle still reconnects on notify_arrival() (USB hotplug).
    m.inotify_fd = ::inotify_init1(IN_CLOEXEC | IN_NONBLOCK);
    if (m.inotify_fd >= 0 && ::inotify_add_watch(m.inotify_fd, "/dev", IN_CREATE | IN_ATTRIB) < 0) {
        ::close(m.inotify_fd);
        m.inotify_fd = -1;
    }
    m.stopping = false;
    m.try_open();
    m.thread = std::thread([&m] { m.run(); });
    return true;
}

void HidHandle::stop() {
    Impl& m = *impl_;
    if (!m.thread.joinable()) return;
    m.stopping = true;
    notify_arrival();
    m.thread.join();
    if (m.dev != nullptr) hid_close(m.dev);
    m.dev = nullptr;
    m.is_connected = false;
    for (int* fd : {&m.wake_fd, &m.inotify_fd}) {
        if (*fd >= 0) ::close(*fd);
        *fd = -1;
    }
}

bool HidHandle::poll(hal::ControlEvent& out) {
    return impl_->ring.pop(out);
}

void HidHandle::notify_arrival() {
    if (impl_->wake_fd < 0) return;
    const std::uint64_t one = 1;
    (void)!::write(impl_->wake_fd, &one, sizeof one);
}

bool HidHandle::connected() const {
    return impl_->is_connected;
}

HidStats HidHandle::stats() const {
    std::lock_guard lock(impl_->stats_mutex);
    return impl_->stats;
}

std::string HidHandle::last_error() const {
    std::lock_guard lock(impl_->stats_mutex);
    return impl_->error;
}

}  // namespace endotower::hid
