// Region-tracking benchmarks (docs/regions.md, docs/performance.md), median and p99:
//  - propagation: the per-frame cost of keeping a marked region anchored at 1920x1080
//    (LK on the region's points + RANSAC homography), drift correction off;
//  - keyframe matching per descriptor at 640x480 and 1920x1080: in a window around
//    the region (drift correction, while tracked) and over the whole frame (recovery,
//    while lost).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "endotower/vision/region_tracker.hpp"
#include "region_test_util.hpp"

namespace {

using namespace endotower;

hal::Frame view(cv::Mat& img, std::uint64_t seq) {
    hal::Frame f;
    f.format = {img.cols, img.rows, static_cast<int>(img.step), hal::PixelFormat::kBgr24};
    f.data = img.data;
    f.sequence = seq;
    f.capture_ns = static_cast<hal::Nanos>(seq) * 16'666'667;
    return f;
}

// A region covering about a sixth of the frame's width, left of centre.
std::vector<vision::Point2> region_for(cv::Size s) {
    const double w = s.width, h = s.height;
    return {{0.30 * w, 0.35 * h}, {0.47 * w, 0.36 * h}, {0.46 * w, 0.62 * h}, {0.31 * w, 0.60 * h}};
}

// A moving view of a textured scene: frame i pans 3 px and turns 0.2 degrees further.
std::vector<cv::Mat> moving_view(cv::Size s, int n) {
    const cv::Mat scene = vision::test::texture(s.width, s.height, 77);
    std::vector<cv::Mat> frames;
    for (int i = 0; i < n; ++i) {
        cv::Mat m = cv::getRotationMatrix2D(cv::Point2f(s.width / 2.f, s.height / 2.f), 0.2 * i, 1.0);
        m.at<double>(0, 2) += 3 * i;
        cv::Mat f;
        cv::warpAffine(scene, f, m, s, cv::INTER_LINEAR, cv::BORDER_REFLECT);
        frames.push_back(f);
    }
    return frames;
}

void report(benchmark::State& state, std::vector<double>& ms, std::size_t tracked) {
    std::sort(ms.begin(), ms.end());
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["tracked_fraction"] = static_cast<double>(tracked) / static_cast<double>(ms.size());
}

// Propagation only: forward and back over 20 frames so the motion never jumps.
void BM_RegionPropagation1080p(benchmark::State& state) {
    const cv::Size size(1920, 1080);
    std::vector<cv::Mat> frames = moving_view(size, 20);
    vision::RegionTracker tracker({.redetect_interval = 0});
    std::string error;
    if (!tracker.mark(0, region_for(size), view(frames[0], 0), error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    std::array<vision::RegionEstimate, 1> out{};
    tracker.track(view(frames[1], 1), out);  // the first frame after marking is matched: not timed
    std::vector<double> ms;
    std::size_t i = 2, tracked = 0;
    for (auto _ : state) {
        const std::size_t k = i % 38, index = k < 20 ? k : 38 - k;
        hal::Frame f = view(frames[index], i++);
        const auto t0 = std::chrono::steady_clock::now();
        tracker.track(f, out);
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        tracked += out[0].state == vision::RegionState::kTracked && !out[0].keyframe_match;
    }
    report(state, ms, tracked);
}
BENCHMARK(BM_RegionPropagation1080p)->Unit(benchmark::kMillisecond)->MinTime(3.0);

// Keyframe matching every frame. range(0): descriptor; range(1): height (480 or 1080);
// range(2): 0 = near the region (propagation off: the book's method per frame),
// 1 = whole frame (the region is not in the picture: recovery search while lost).
void BM_RegionKeyframe(benchmark::State& state) {
    const auto descriptor = static_cast<vision::RegionDescriptor>(state.range(0));
    const cv::Size size = state.range(1) == 480 ? cv::Size(640, 480) : cv::Size(1920, 1080);
    const bool whole = state.range(2) != 0;
    std::vector<cv::Mat> frames = moving_view(size, 8);
    cv::Mat elsewhere = vision::test::texture(size.width, size.height, 78);
    vision::RegionTracker tracker({.descriptor = descriptor, .propagate = false});
    std::string error;
    if (!tracker.mark(0, region_for(size), view(frames[0], 0), error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    std::array<vision::RegionEstimate, 1> out{};
    std::vector<double> ms;
    std::size_t i = 1, tracked = 0;
    for (auto _ : state) {
        hal::Frame f = whole ? view(elsewhere, i) : view(frames[1 + i % 7], i);
        ++i;
        const auto t0 = std::chrono::steady_clock::now();
        tracker.track(f, out);
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        tracked += out[0].state == vision::RegionState::kTracked;
    }
    report(state, ms, tracked);
    state.SetLabel(std::string(vision::to_string(descriptor)) + (whole ? " whole frame" : " near the region"));
}
BENCHMARK(BM_RegionKeyframe)
    ->ArgsProduct({{0, 1, 2}, {480, 1080}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
