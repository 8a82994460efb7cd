// Heap allocations of the whole process (every thread) for the benchmarks, counted from
// the program's start by the tests' counters (tests/common/heap_counter.hpp, switched on
// here before main): operator new (the project's per-frame rule) and, apart, the C
// allocator (malloc, calloc, realloc, posix_memalign, aligned_alloc, memalign: OpenCV's
// buffers and libjpeg's pools come from there; operator new's own are not in it).
// A benchmark reads the difference across its timed frames.
#pragma once

#include <cstdint>

namespace endotower::bench {
std::int64_t allocations();
std::int64_t c_allocations();
}  // namespace endotower::bench
