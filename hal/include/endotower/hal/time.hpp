// Time values shared by every layer: nanoseconds on the monotonic clock.
#pragma once

#include <cstdint>

namespace endotower::hal {

// Nanoseconds since an arbitrary epoch of CLOCK_MONOTONIC (or the virtual clock's
// epoch in simulation). Signed so that differences need no casts.
using Nanos = std::int64_t;

constexpr Nanos kMillisecond = 1'000'000;
constexpr Nanos kSecond = 1'000'000'000;

}  // namespace endotower::hal
