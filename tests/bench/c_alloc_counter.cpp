#include "c_alloc_counter.hpp"

#include <atomic>
#include <cstddef>

namespace {
std::atomic<std::int64_t> g_c_allocations{0};
void note() {
    g_c_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

namespace endotower::bench {
std::int64_t c_allocations() {
    return g_c_allocations.load(std::memory_order_relaxed);
}
}  // namespace endotower::bench

extern "C" {
// glibc's own entry points, which the interposed functions forward to.
// NOLINTBEGIN(bugprone-reserved-identifier)
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
// NOLINTEND(bugprone-reserved-identifier)

void* malloc(std::size_t n) {
    note();
    return __libc_malloc(n);
}
void* calloc(std::size_t a, std::size_t b) {
    note();
    return __libc_calloc(a, b);
}
void* realloc(void* p, std::size_t n) {
    note();
    return __libc_realloc(p, n);
}
int posix_memalign(void** out, std::size_t align, std::size_t n) {
    note();
    void* p = __libc_memalign(align, n);
    if (!p) return 12;  // ENOMEM
    *out = p;
    return 0;
}
void* aligned_alloc(std::size_t align, std::size_t n) {
    note();
    return __libc_memalign(align, n);
}
void* memalign(std::size_t align, std::size_t n) {
    note();
    return __libc_memalign(align, n);
}
}
