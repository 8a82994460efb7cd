// CPU cost per frame of V4L2 capture (next() + release(): poll, DQBUF, QBUF) on the
// kernel's vivid driver at 1920x1080p60 YUYV, and heap allocations per frame after
// the start. Needs vivid: run it in the qemu guest,
//   tests/driver/run-in-guest.sh --modules vivid:n_devs=1 --
//   build/release/tests/bench/bench_capture
// Under TCG emulation the figures are a report, not a goal (docs/performance.md).
// On a board: ENDOTOWER_BENCH_CAPTURE=/dev/videoN (see the variables below).
// "CPU" is the process's CPU time per frame (every thread); "Time" is wall time per
// frame, i.e. the frame period while the source keeps up.
//
// BM_DecodeMjpeg1080pQ90 runs on the host (no device): MjpegDecoder on one 1920x1080
// frame encoded at quality 90 (cv::imencode, 4:2:0), the real endoscope frame
// ../shared/data/endovis17_demo/frame.png when present, else a generated picture (the
// label says which). allocs_per_frame counts operator new, c_allocs_per_frame the C
// allocator (libjpeg's), both after three warm-up frames.
#include <benchmark/benchmark.h>
#include <time.h>

#include <cstdlib>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "endotower/v4l2/mjpeg_decoder.hpp"
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

void BM_DecodeMjpeg1080pQ90(benchmark::State& state) {
    constexpr int kWidth = 1920, kHeight = 1080;
    cv::Mat picture =
        cv::imread(ENDOTOWER_SHARED_DATA "/endovis17_demo/frame.png", cv::IMREAD_COLOR);
    const bool real = !picture.empty() && picture.cols == kWidth && picture.rows == kHeight;
    if (!real) {  // gradients and a few edges; compresses better than real tissue
        picture.create(kHeight, kWidth, CV_8UC3);
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                picture.at<cv::Vec3b>(y, x) = {
                    static_cast<std::uint8_t>(x * 255 / kWidth),
                    static_cast<std::uint8_t>(y * 255 / kHeight),
                    static_cast<std::uint8_t>(((x / 64 + y / 64) % 2) * 200)};
    }
    std::vector<std::uint8_t> jpeg;
    cv::imencode(".jpg", picture, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
    std::vector<std::uint8_t> frame(static_cast<std::size_t>(kWidth) * kHeight * 3);
    v4l2::MjpegDecoder decoder("bench");
    auto decode = [&](std::uint64_t seq) {
        return decoder.decode(jpeg.data(), jpeg.size(), seq, frame.data(), kWidth, kHeight,
                              kWidth * 3);
    };
    for (std::uint64_t i = 0; i < 3; ++i)
        if (decode(i) != v4l2::MjpegResult::kDecoded) {
            state.SkipWithError(decoder.message().c_str());
            return;
        }
    // Counted around decode() only: the benchmark library allocates between repetitions.
    std::int64_t frames = 0, allocs = 0, c_allocs = 0;
    for (auto _ : state) {
        const std::int64_t a0 = bench::allocations(), c0 = bench::c_allocations();
        const v4l2::MjpegResult r = decode(static_cast<std::uint64_t>(frames));
        allocs += bench::allocations() - a0;
        c_allocs += bench::c_allocations() - c0;
        if (r != v4l2::MjpegResult::kDecoded) {
            state.SkipWithError(decoder.message().c_str());
            break;
        }
        benchmark::DoNotOptimize(frame[frame.size() / 2]);
        ++frames;
    }
    const double n = frames > 0 ? static_cast<double>(frames) : 1.0;
    state.counters["allocs_per_frame"] = static_cast<double>(allocs) / n;
    state.counters["c_allocs_per_frame"] = static_cast<double>(c_allocs) / n;
    state.counters["jpeg_kB"] = static_cast<double>(jpeg.size()) / 1024.0;
    state.counters["arena_kB"] = static_cast<double>(decoder.arena_bytes()) / 1024.0;
    state.SetLabel(real ? "endovis17_demo/frame.png" : "generated picture");
}
BENCHMARK(BM_DecodeMjpeg1080pQ90)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(9)
    ->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
