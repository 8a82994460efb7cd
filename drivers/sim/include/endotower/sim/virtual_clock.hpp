// VirtualClock: simulation owns time. now() moves only through sleep_until() or
// advance(), so a replay gives the same output bit for bit and runs as fast as the
// CPU allows.
#pragma once

#include <atomic>

#include "endotower/hal/clock.hpp"

namespace endotower::sim {

class VirtualClock final : public hal::Clock {
public:
    explicit VirtualClock(hal::Nanos start_ns = 0) : now_(start_ns) {}

    hal::Nanos now() const override { return now_.load(std::memory_order_acquire); }
    // Moves time forward to t (never back).
    void sleep_until(hal::Nanos t) override;
    void advance(hal::Nanos dt) { sleep_until(now() + dt); }
    bool is_virtual() const override { return true; }

private:
    std::atomic<hal::Nanos> now_;
};

}  // namespace endotower::sim
