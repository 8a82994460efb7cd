// Clock: the source of "now" for the whole firmware, injectable so that simulation
// owns time (ArduPilot SITL style) and replay is deterministic.
#pragma once

#include "endotower/hal/time.hpp"

namespace endotower::hal {

class Clock {
public:
    virtual ~Clock() = default;

    // Current time in nanoseconds. Monotonic, never goes back.
    virtual Nanos now() const = 0;

    // Blocks until now() >= t. A virtual clock advances to t and returns at once.
    virtual void sleep_until(Nanos t) = 0;

    // True when time only moves through sleep_until() (deterministic simulation):
    // callers may then wait for work to finish instead of racing a deadline.
    virtual bool is_virtual() const = 0;
};

}  // namespace endotower::hal
