// Interposes glibc's malloc family over its __libc_ entry points and replaces operator
// new (which then allocates through __libc_malloc, so each allocation counts once).
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

namespace {
std::atomic<long> g_count{0};
std::atomic<bool> g_on{false};
[[maybe_unused]] void note() {
    if (g_on.load(std::memory_order_relaxed)) g_count.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

namespace endotower::v4l2::test {
void set_counting(bool on) {
    if (on) g_count = 0;
    g_on = on;
}
long heap_allocations() {
    return ENDOTOWER_SANITIZED ? -1 : g_count.load();
}
}  // namespace endotower::v4l2::test

#if !ENDOTOWER_SANITIZED
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

namespace {
void* counted_new(std::size_t n) {
    note();
    if (void* p = __libc_malloc(n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
}  // namespace
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
#endif
