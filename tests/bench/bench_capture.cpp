// CPU cost per frame of V4L2 capture (next() + release(): poll, DQBUF, QBUF) on the
// kernel's vivid driver at 1920x1080p60 YUYV, and heap allocations per frame after
// the start. Needs vivid: run it in the qemu guest,
//   tests/driver/run-in-guest.sh --modules vivid:n_devs=1 --
//   build/release/tests/bench/bench_capture
// Under TCG emulation the figures are a report, not a goal (docs/performance.md).
// On a board: ENDOTOWER_BENCH_CAPTURE=/dev/videoN (see the variables below).
// "CPU" is the process's CPU time per frame (every thread); "Time" is wall time per
// frame, i.e. the frame period while the source keeps up.
#include <benchmark/benchmark.h>
#include <time.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "alloc_counter.hpp"
#include "endotower/v4l2/v4l2_capture.hpp"

namespace {

using namespace endotower;

void BM_CaptureVivid1080p60Yuyv(benchmark::State& state) {
    v4l2::V4l2CaptureConfig c;
    c.input = 3;
    c.dv_timings = "1920x1080p60";
    if (const char* dev = std::getenv("ENDOTOWER_BENCH_CAPTURE")) {
        // A real board: ENDOTOWER_BENCH_CAPTURE=/dev/video0 [ENDOTOWER_BENCH_INPUT=N]
        // [ENDOTOWER_BENCH_DV=query|1920x1080p60|""] [ENDOTOWER_BENCH_FORMAT=uyvy].
        c.device = dev;
        c.input = std::getenv("ENDOTOWER_BENCH_INPUT")
                      ? std::atoi(std::getenv("ENDOTOWER_BENCH_INPUT"))
                      : -1;
        c.dv_timings = std::getenv("ENDOTOWER_BENCH_DV") ? std::getenv("ENDOTOWER_BENCH_DV") : "";
        if (const char* f = std::getenv("ENDOTOWER_BENCH_FORMAT"))
            v4l2::parse_capture_format(f, c.format);
    } else {
        std::ifstream name("/sys/class/video4linux/video0/name");
        std::string n;
        std::getline(name, n);
        if (n.rfind("vivid", 0) != 0) {
            state.SkipWithError(
                "needs /dev/video0 = vivid (run through tests/driver/run-in-guest.sh) "
                "or ENDOTOWER_BENCH_CAPTURE=DEVICE");
            return;
        }
    }
    v4l2::V4l2Capture cap(c);
    if (!cap.start()) {
        state.SkipWithError(cap.error().c_str());
        return;
    }
    hal::Frame f;
    for (int i = 0; i < 10; ++i)  // warm-up: the stream settles
        if (cap.next(f, hal::kSecond) == hal::SourceStatus::kFrame) cap.release(f);
    const std::int64_t a0 = bench::allocations();
    std::int64_t frames = 0;
    double thread_cpu_ns = 0;
    for (auto _ : state) {
        timespec c0{}, c1{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
        const hal::SourceStatus s = cap.next(f, hal::kSecond);
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
        thread_cpu_ns +=
            static_cast<double>((c1.tv_sec - c0.tv_sec) * hal::kSecond + (c1.tv_nsec - c0.tv_nsec));
        if (s != hal::SourceStatus::kFrame) {
            state.SkipWithError(("no frame: " + cap.error()).c_str());
            break;
        }
        benchmark::DoNotOptimize(f.data[0]);
        cap.release(f);
        ++frames;
    }
    state.counters["allocs_per_frame"] =
        frames > 0 ? static_cast<double>(bench::allocations() - a0) / static_cast<double>(frames)
                   : 0.0;
    // CPU time of next() itself on this thread (poll, DQBUF, QBUF of skipped frames).
    state.counters["next_cpu_us"] =
        frames > 0 ? thread_cpu_ns / 1e3 / static_cast<double>(frames) : 0.0;
    state.counters["driver_drops"] = static_cast<double>(cap.stats().drops);
    state.counters["skipped"] = static_cast<double>(cap.stats().skipped);
}
BENCHMARK(BM_CaptureVivid1080p60Yuyv)->Iterations(300)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
