// Counts heap allocations of the whole process (every thread) by replacing the
// global operator new. Only linked into benchmarks.
#pragma once

#include <atomic>
#include <cstdint>

namespace endotower::bench {
std::int64_t allocations();
}  // namespace endotower::bench
