// Counts the heap allocations of the whole test program while counting is on: the C
// allocator (libjpeg's pools come from malloc) and operator new. Linked only into
// test_mjpeg. Under ASan/TSan the sanitizer owns malloc: counts read -1.
#pragma once

namespace endotower::v4l2::test {
void set_counting(bool on);  // on: resets the counts
long heap_allocations();     // malloc family + operator new since counting started, or -1
}  // namespace endotower::v4l2::test
