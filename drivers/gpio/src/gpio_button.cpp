#include "endotower/gpio/gpio_button.hpp"

#include <gpiod.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <mutex>
#include <thread>

#include "endotower/system/spsc_ring.hpp"
#include "endotower/system/syscall.hpp"

namespace endotower::gpio {

namespace {
hal::Nanos monotonic_now() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * hal::kSecond + ts.tv_nsec;
}
}  // namespace

struct GpioButton::Impl {
    GpioButtonConfig config;
    gpiod_chip* chip = nullptr;
    gpiod_line* line = nullptr;
    int event_fd = -1, wake_fd = -1;
    std::thread thread;
    std::atomic<bool> stopping{false};
    system::SpscRing<hal::ControlEvent, 64> ring;
    mutable std::mutex stats_mutex;
    GpioStats stats;

    std::string where() const {
        return "GPIO " + config.chip + " line " + std::to_string(config.line);
    }

    void run(ButtonDebouncer debouncer) {
        gpiod_line_event events[16];
        while (!stopping) {
            const hal::Nanos d = debouncer.deadline();
            int timeout_ms = -1;
            if (d >= 0) {
                const hal::Nanos left = d - monotonic_now();
                timeout_ms =
                    left <= 0
                        ? 0
                        : static_cast<int>((left + hal::kMillisecond - 1) / hal::kMillisecond);
            }
            pollfd fds[2] = {{event_fd, POLLIN, 0}, {wake_fd, POLLIN, 0}};
            if (system::retry_eintr([&] { return ::poll(fds, 2, timeout_ms); }) < 0) return;
            std::uint64_t edges = 0;
            if (fds[0].revents & POLLIN) {
                const int n = gpiod_line_event_read_fd_multiple(event_fd, events, 16);
                for (int i = 0; i < n; ++i) {
                    const hal::Nanos t = events[i].ts.tv_sec * hal::kSecond + events[i].ts.tv_nsec;
                    debouncer.edge(events[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE, t);
                }
                edges = n > 0 ? static_cast<std::uint64_t>(n) : 0;
            }
            hal::ControlEvent e;
            std::uint64_t queued = 0, dropped = 0;
            while (debouncer.next(monotonic_now(), e)) (ring.push(e) ? queued : dropped) += 1;
            std::lock_guard lock(stats_mutex);
            stats.edges += edges;
            stats.events += queued;
            stats.dropped += dropped;
            stats.glitches = debouncer.glitches();
        }
    }

    void close_all() {
        if (line != nullptr) gpiod_line_release(line);
        if (chip != nullptr) gpiod_chip_close(chip);
        if (wake_fd >= 0) ::close(wake_fd);
        line = nullptr;
        chip = nullptr;
        wake_fd = event_fd = -1;
    }
};

GpioButton::GpioButton(GpioButtonConfig config) : impl_(std::make_unique<Impl>()) {
    impl_->config = std::move(config);
}

GpioButton::~GpioButton() {
    stop();
}

bool GpioButton::start(std::string& error) {
    Impl& m = *impl_;
    if (m.thread.joinable()) return true;
    m.chip = gpiod_chip_open_lookup(m.config.chip.c_str());
    if (m.chip == nullptr) {
        error = system::errno_message("gpiod_chip_open_lookup", m.config.chip, errno) +
                "; check button.chip (gpiodetect lists the chips)";
        return false;
    }
    m.line = gpiod_chip_get_line(m.chip, m.config.line);
    if (m.line == nullptr) {
        error = m.where() + ": " +
                system::errno_message("gpiod_chip_get_line", gpiod_chip_name(m.chip), errno) +
                " (the chip has " + std::to_string(gpiod_chip_num_lines(m.chip)) + " lines)";
        m.close_all();
        return false;
    }
    const int flags = m.config.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    if (gpiod_line_request_both_edges_events_flags(m.line, m.config.consumer.c_str(), flags) < 0) {
        error =
            m.where() + ": " +
            system::errno_message("gpiod_line_request_both_edges_events", "", errno) +
            (errno == EBUSY ? " (the line is used by another consumer; gpioinfo shows which)" : "");
        m.line = nullptr;  // not requested: nothing to release
        m.close_all();
        return false;
    }
    const int level = gpiod_line_get_value(m.line);
    m.event_fd = gpiod_line_event_get_fd(m.line);
    m.wake_fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (level < 0 || m.event_fd < 0 || m.wake_fd < 0) {
        error = m.where() + ": " + system::errno_message("gpiod_line_get_value/eventfd", "", errno);
        m.close_all();
        return false;
    }
    m.stopping = false;
    ButtonDebouncer debouncer(m.config.debounce, level == 1);
    m.thread = std::thread([&m, debouncer] { m.run(debouncer); });
    return true;
}

void GpioButton::stop() {
    Impl& m = *impl_;
    if (!m.thread.joinable()) return;
    m.stopping = true;
    const std::uint64_t one = 1;
    (void)!::write(m.wake_fd, &one, sizeof one);
    m.thread.join();
    m.close_all();
}

bool GpioButton::poll(hal::ControlEvent& out) {
    return impl_->ring.pop(out);
}

GpioStats GpioButton::stats() const {
    std::lock_guard lock(impl_->stats_mutex);
    return impl_->stats;
}

}  // namespace endotower::gpio
