// Heap allocation counters for the no-allocation tests (heap_counter.cpp, linked into
// the test programs that use them): operator new calls (the project's per-frame rule)
// and, apart, C allocator calls (OpenCV's internal buffers come from posix_memalign),
// counted while set_counting(true) is in force. -1 under ASan/TSan (not counted there).
#pragma once

namespace endotower::vision::test {

long heap_allocations();
long c_allocations();
void set_counting(bool on);  // on: resets both counts

}  // namespace endotower::vision::test
