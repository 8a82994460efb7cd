// Heap allocation counters for the no-allocation tests (the object library
// endotower_heap_counter, linked into the test programs that use it): operator new calls
// (the project's per-frame rule) and, apart, C allocator calls (OpenCV's internal
// buffers come from posix_memalign, libjpeg's pools from malloc), counted while
// set_counting(true) is in force. Each allocation counts once: operator new allocates
// through glibc's own entry point, not the counted malloc. -1 under ASan/TSan (not
// counted there).
#pragma once

namespace endotower::test {

long heap_allocations();
long c_allocations();
void set_counting(bool on);  // on: resets both counts

}  // namespace endotower::test
