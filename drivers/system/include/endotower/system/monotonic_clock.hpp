// MonotonicClock: CLOCK_MONOTONIC, the clock V4L2 and DRM stamp their events with,
// so capture and page-flip timestamps compare directly with now().
#pragma once

#include "endotower/hal/clock.hpp"

namespace endotower::system {

class MonotonicClock final : public hal::Clock {
public:
    hal::Nanos now() const override;
    // clock_nanosleep(TIMER_ABSTIME), resumed after signals.
    void sleep_until(hal::Nanos t) override;
    bool is_virtual() const override { return false; }
};

}  // namespace endotower::system
