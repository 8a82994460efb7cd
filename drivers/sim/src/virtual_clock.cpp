#include "endotower/sim/virtual_clock.hpp"

namespace endotower::sim {

void VirtualClock::sleep_until(hal::Nanos t) {
    // Several threads may wait on the same clock: only ever move forward, so a late
    // sleeper cannot drag time back below an earlier one's target.
    hal::Nanos cur = now_.load(std::memory_order_acquire);
    while (cur < t && !now_.compare_exchange_weak(cur, t, std::memory_order_acq_rel,
                                                  std::memory_order_acquire)) {
    }
}

}  // namespace endotower::sim
