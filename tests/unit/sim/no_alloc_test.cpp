// The per-frame paths allocate nothing in steady state. Counts operator new calls
// (C++ allocations) around them; replacing the global operator new here affects the
// whole test binary, but it only counts while a NoAllocScope is alive.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "endotower/sim/compositor.hpp"
#include "endotower/sim/recorded_source.hpp"
#include "endotower/sim/scripted_input.hpp"
#include "endotower/sim/virtual_clock.hpp"
#include "test_util.hpp"

// clang's ThreadSanitizer (the tsan preset) links its own operator new and delete
// into every program whole, so this file cannot replace them there: under TSan the
// paths below still run, only the counts are not taken.
#if defined(__SANITIZE_THREAD__)
#define ENDOTOWER_COUNTS_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define ENDOTOWER_COUNTS_ALLOCATIONS 0
#endif
#endif
#ifndef ENDOTOWER_COUNTS_ALLOCATIONS
#define ENDOTOWER_COUNTS_ALLOCATIONS 1
#endif

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
constexpr bool kCounted = ENDOTOWER_COUNTS_ALLOCATIONS != 0;
}  // namespace

#if ENDOTOWER_COUNTS_ALLOCATIONS
// Every non-aligned form is replaced, so that new and delete always pair up (a
// sanitizer's own nothrow new must not meet this file's delete).
void* operator new(std::size_t n) {
    if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1);
    if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
    return operator new(n);
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
    try {
        return operator new(n);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept {
    return operator new(n, t);
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
void operator delete(void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
#endif

namespace endotower::sim {
namespace {

class NoAllocScope {
public:
    NoAllocScope() {
        g_allocations = 0;
        g_counting = true;
    }
    ~NoAllocScope() { g_counting = false; }
    long count() const { return g_allocations.load(); }
};

// No allocation in the scope, where they are counted (not under TSan).
void expect_none(const NoAllocScope& scope) {
    if (kCounted) {
        EXPECT_EQ(scope.count(), 0);
    }
}

TEST(NoAlloc, CounterSeesAllocations) {
    if (!kCounted) GTEST_SKIP() << "operator new is TSan's own here";
    NoAllocScope scope;
    auto* v = new std::vector<int>(100);
    // Keep the optimiser from eliding the pair.
    asm volatile("" : : "r"(v) : "memory");
    delete v;
    EXPECT_EQ(scope.count(), 2);  // the vector and its buffer
}

TEST(NoAlloc, ComposeAndBlend) {
    const int w = 640, h = 480;
    std::vector<std::uint8_t> video(w * h * 3, 90), out(w * h * 3), rgba(w * h * 4, 128);
    hal::Frame f;
    f.format = hal::FrameFormat{w, h, w * 3, hal::PixelFormat::kBgr24};
    f.data = video.data();
    hal::OverlayLayer ov;
    ov.width = w, ov.height = h, ov.stride = w * 4, ov.rgba = rgba.data();
    ov.rects[0] = hal::Rect{10, 10, 100, 50};
    ov.rects[1] = hal::Rect{50, 30, 300, 200};
    ov.rect_count = 2;
    NoAllocScope scope;
    for (int i = 0; i < 10; ++i) {
        ASSERT_TRUE(compose(f, &ov, out.data(), w * 3));
        ASSERT_TRUE(blend_in_place(f.format, out.data(), ov));
    }
    expect_none(scope);
}

TEST(NoAlloc, ScriptedInputPoll) {
    Timeline tl;
    std::string error;
    ASSERT_TRUE(parse_timeline("frame 1 press\nframe 2 release\nt 0.5 wheel 3\n", "x", tl, error));
    VirtualClock clock;
    ScriptedInput input(tl, clock, 0, 25.0);
    NoAllocScope scope;
    hal::ControlEvent ev;
    int n = 0;
    for (int i = 0; i < 20; ++i) {
        clock.advance(40 * hal::kMillisecond);
        while (input.poll(ev)) ++n;
    }
    EXPECT_EQ(n, 3);
    expect_none(scope);
}

TEST(NoAlloc, RecordedVideoNextAndRelease) {
    test::TempDir dir("noalloc");
    const std::string path = dir.file("clip.mkv");
    {
        cv::VideoWriter writer(path, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'),
                               25.0, cv::Size(64, 48), true);
        ASSERT_TRUE(writer.isOpened());
        for (int i = 0; i < 20; ++i)
            writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i)));
    }
    VirtualClock clock;
    RecordedFrameSource src({path, 0.0, 3}, clock);
    ASSERT_TRUE(src.start()) << src.error();
    hal::Frame f;
    ASSERT_EQ(src.next(f, 0), hal::SourceStatus::kFrame);  // the staged first frame
    src.release(f);
    NoAllocScope scope;
    for (int i = 1; i < 20; ++i) {
        ASSERT_EQ(src.next(f, 0), hal::SourceStatus::kFrame);
        src.release(f);
    }
    expect_none(scope);
}

}  // namespace
}  // namespace endotower::sim
