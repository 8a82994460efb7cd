// Calibration benchmarks (docs/performance.md): the per-frame costs the calibration
// adds to the video path at 1920x1080: the undistortion remap (fixed-point maps, the
// shipped path; float maps for comparison) and the field-of-view check. Median and
// p99 per frame, and heap allocations per frame in steady state.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "alloc_counter.hpp"
#include "endotower/calibration/fov_monitor.hpp"
#include "endotower/calibration/undistorter.hpp"

namespace {

using namespace endotower;

// A 1080p endoscope-like frame: textured disc of radius 530 px, black outside.
cv::Mat frame_1080p() {
    cv::Mat img(1080, 1920, CV_8UC3);
    cv::randn(img, cv::Scalar(85, 75, 185), cv::Scalar(20, 20, 20));
    cv::Mat mask = cv::Mat::zeros(img.size(), CV_8UC1);
    cv::circle(mask, cv::Point(960, 540), 530, 255, cv::FILLED);
    img.setTo(cv::Scalar::all(0), ~mask);
    return img;
}

// The simulator's default lens at 1080p (docs/scenario.md), as a book-model file.
calibration::Calibration scope_1080p() {
    calibration::Calibration c;
    c.scope = "bench";
    c.model = calibration::LensModel::kBook;
    c.width = 1920, c.height = 1080;
    c.fx = 937.4, c.fy = 925.6, c.cx = 973.5, c.cy = 530.5;
    const double h = 1080;
    c.distortion = {0, 0.32 / (h * h), -0.06 / (h * h * h * h)};
    c.fov = {959.5, 539.5, 529.2};
    return c;
}

void record(benchmark::State& state, std::vector<double>& ms, std::int64_t allocs,
            std::int64_t frames) {
    std::sort(ms.begin(), ms.end());
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["allocs_per_frame"] = static_cast<double>(allocs) / static_cast<double>(frames);
}

// Arg 0: the shipped fixed-point maps (Undistorter); 1: OpenCV remap with float maps
// (its thread pool); 2: the same on one thread; 3: OpenCV remap with fixed-point maps,
// one thread; 4: Undistorter with its helper thread (set_threads(2)); 5: Undistorter,
// one thread, the SSE2 loop forced (0 and 4 use the widest this CPU runs: AVX2 here).
void BM_Undistort1080p(benchmark::State& state) {
    const calibration::Calibration c = scope_1080p();
    calibration::Undistorter u;
    std::string error;
    if (!u.init(c, error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    cv::Mat in = frame_1080p(), out(in.size(), in.type());
    cv::Mat fx(in.size(), CV_32FC1), fy(in.size(), CV_32FC1);
    for (int y = 0; y < in.rows; ++y)
        for (int x = 0; x < in.cols; ++x) {
            const calibration::Point2 s = u.source_of(x, y);
            fx.at<float>(y, x) = static_cast<float>(s.x);
            fy.at<float>(y, x) = static_cast<float>(s.y);
        }
    cv::Mat m1, m2;
    cv::convertMaps(fx, fy, m1, m2, CV_16SC2);
    // A ring of 4 capture and 4 output buffers, as the V4L2 queue and the display hand
    // them over: 50 MB, so a frame is not still in the last-level cache from the
    // previous iteration (the same buffer every time would flatter any remap).
    constexpr int kRing = 4;
    std::vector<cv::Mat> ins, outs;
    for (int i = 0; i < kRing; ++i) {
        ins.push_back(in.clone());
        outs.push_back(out.clone());
    }
    hal::Frame fi, fo;
    fi.format = fo.format = {1920, 1080, 1920 * 3, hal::PixelFormat::kBgr24};
    fi.data = in.data;
    fo.data = out.data;
    std::vector<double> ms;
    ms.reserve(100000);
    if (state.range(0) == 4) u.set_threads(2);
    if (state.range(0) == 5) u.set_kernel(calibration::Undistorter::Kernel::kSse2);
    u.apply(fi, fo);  // warm-up
    const std::int64_t a0 = bench::allocations();
    std::int64_t n = 0;
    const int threads = cv::getNumThreads();
    if (state.range(0) >= 2) cv::setNumThreads(1);
    for (auto _ : state) {
        const cv::Mat& src = ins[n % kRing];
        cv::Mat& dst = outs[n % kRing];
        fi.data = src.data;
        fo.data = dst.data;
        const auto t0 = std::chrono::steady_clock::now();
        if (state.range(0) == 0 || state.range(0) == 4 || state.range(0) == 5)
            u.apply(fi, fo);
        else if (state.range(0) == 3)
            cv::remap(src, dst, m1, m2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
        else
            cv::remap(src, dst, fx, fy, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        ++n;
    }
    cv::setNumThreads(threads);
    record(state, ms, bench::allocations() - a0, n);
}
BENCHMARK(BM_Undistort1080p)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Arg(3)
    ->Arg(4)
    ->Arg(5)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3.0);

void BM_FovCheck1080p(benchmark::State& state) {
    const cv::Mat in = frame_1080p();
    calibration::FovMonitor monitor({959.5, 539.5, 530});
    hal::Frame f;
    f.format = {1920, 1080, 1920 * 3, hal::PixelFormat::kBgr24};
    f.data = in.data;
    std::vector<double> ms;
    ms.reserve(1000000);
    int ok = 0;
    const std::int64_t a0 = bench::allocations();
    std::int64_t n = 0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        ok += monitor.check(f).status == calibration::FovStatus::kOk;
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        ++n;
    }
    record(state, ms, bench::allocations() - a0, n);
    state.counters["ok_fraction"] = static_cast<double>(ok) / static_cast<double>(n);
}
BENCHMARK(BM_FovCheck1080p)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

// mask_outside on the analysis copy of a 1080p BGR frame (the circle of the sim's lens).
void BM_FovMask1080p(benchmark::State& state) {
    cv::Mat in = frame_1080p();
    hal::Frame f;
    f.format = {1920, 1080, 1920 * 3, hal::PixelFormat::kBgr24};
    f.data = in.data;
    std::vector<double> ms;
    ms.reserve(1000000);
    const std::int64_t a0 = bench::allocations();
    std::int64_t n = 0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        calibration::mask_outside(f, {959.5, 539.5, 530});
        benchmark::DoNotOptimize(in.data);
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        ++n;
    }
    record(state, ms, bench::allocations() - a0, n);
}
BENCHMARK(BM_FovMask1080p)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
