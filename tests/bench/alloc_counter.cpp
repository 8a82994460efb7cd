#include "alloc_counter.hpp"

#include "heap_counter.hpp"

namespace {
// On for the whole run (the benchmarks take differences, never reset); read below so
// the initializer is kept.
const bool g_counting = (endotower::test::set_counting(true), true);
}  // namespace

namespace endotower::bench {
std::int64_t allocations() {
    return g_counting ? test::heap_allocations() : 0;
}
std::int64_t c_allocations() {
    return g_counting ? test::c_allocations() : 0;
}
}  // namespace endotower::bench
