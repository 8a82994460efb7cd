// Counts calls into the C allocator (malloc, calloc, realloc, posix_memalign,
// aligned_alloc, memalign) of the whole process by interposing glibc's entry points:
// libraries such as libjpeg allocate there, out of operator new's sight. The count
// includes the mallocs behind operator new. Linked into bench_capture and bench_gestures.
#pragma once

#include <cstdint>

namespace endotower::bench {
std::int64_t c_allocations();
}  // namespace endotower::bench
