#include "endotower/system/monotonic_clock.hpp"

#include <time.h>

#include <cerrno>

namespace endotower::system {

hal::Nanos MonotonicClock::now() const {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<hal::Nanos>(ts.tv_sec) * hal::kSecond + ts.tv_nsec;
}

void MonotonicClock::sleep_until(hal::Nanos t) {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(t / hal::kSecond);
    ts.tv_nsec = static_cast<long>(t % hal::kSecond);
    // clock_nanosleep returns the error number instead of setting errno.
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
}

}  // namespace endotower::system
