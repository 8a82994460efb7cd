// Counts heap allocations of the whole process, separately: operator new (C++
// allocations, the project's rule) and the C allocator (OpenCV's internal buffers
// come from posix_memalign), by replacing operator new and interposing glibc's malloc
// family over its __libc_ entry points. Linked into the vision tests that count
// (test_vision, test_gesture_golden, test_region_propagation, test_book_trackers),
// test_mjpeg and the benchmarks (tests/bench/alloc_counter.cpp).
// Under ASan/TSan the sanitizer owns malloc: the C allocator is not interposed there
// and neither is operator new: both counts read -1 (the tests then do not assert them).
#include "heap_counter.hpp"

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

// GCC names its sanitizers with macros, clang (the sanitizer presets) with __has_feature.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define ENDOTOWER_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define ENDOTOWER_SANITIZED 1
#endif
#endif
#ifndef ENDOTOWER_SANITIZED
#define ENDOTOWER_SANITIZED 0
#endif

#if !ENDOTOWER_SANITIZED
extern "C" {
// glibc's own entry points, which the interposed functions forward to.
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
}
#endif

namespace {
std::atomic<long> g_count{0}, g_new_count{0};
std::atomic<bool> g_on{false};
[[maybe_unused]] void note() {
    if (g_on.load(std::memory_order_relaxed)) g_count.fetch_add(1, std::memory_order_relaxed);
}
#if !ENDOTOWER_SANITIZED
// operator new's allocations, from glibc's own entry points (not the counted malloc).
void* counted_new(std::size_t n) {
    if (g_on.load(std::memory_order_relaxed)) g_new_count.fetch_add(1, std::memory_order_relaxed);
    if (void* p = __libc_malloc(n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
void* counted_new(std::size_t n, std::align_val_t a) {
    if (g_on.load(std::memory_order_relaxed)) g_new_count.fetch_add(1, std::memory_order_relaxed);
    if (void* p = __libc_memalign(static_cast<std::size_t>(a), n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
#endif
}  // namespace

namespace endotower::test {
long heap_allocations() {
    return ENDOTOWER_SANITIZED ? -1 : g_new_count.load();
}
long c_allocations() {
    return ENDOTOWER_SANITIZED ? -1 : g_count.load();
}
void set_counting(bool on) {
    if (on) g_count = g_new_count = 0;
    g_on = on;
}
}  // namespace endotower::test

#if !ENDOTOWER_SANITIZED
extern "C" {
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
#endif

#if !ENDOTOWER_SANITIZED
void* operator new(std::size_t n) {
    return counted_new(n);
}
void* operator new[](std::size_t n) {
    return counted_new(n);
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}
void* operator new(std::size_t n, std::align_val_t a) {
    return counted_new(n, a);
}
void* operator new[](std::size_t n, std::align_val_t a) {
    return counted_new(n, a);
}
void operator delete(void* p, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
    std::free(p);
}
#endif
