// Tool-tracking benchmarks (docs/performance.md): the analysis-path cost per frame
// of the trackers at 1920x1080, on a simulator-like frame (a dark shaft over
// textured tissue), median and p99.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "endotower/vision/area_mean.hpp"
#include "endotower/vision/kalman_tool_tracker.hpp"
#include "endotower/vision/likelihood_tool_tracker.hpp"
#include "endotower/vision/tool_tracker_factory.hpp"

namespace {

using namespace endotower;

// Tracks the frames round-robin, one per iteration; median and p99 per frame, and the
// fraction of frames where a tool was found.
void time_tracking(benchmark::State& state, vision::ToolTracker& tracker,
                   const std::vector<cv::Mat>& frames, const hal::FrameFormat& fmt) {
    std::array<vision::ToolEstimate, vision::ToolTracker::kMaxTools> out{};
    std::vector<double> ms;
    ms.reserve(100000);
    std::size_t i = 0, found = 0;
    for (auto _ : state) {
        hal::Frame f;
        f.format = fmt;
        f.data = frames[i++ % frames.size()].data;
        const auto t0 = std::chrono::steady_clock::now();
        found += tracker.track(f, out);
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
    }
    std::sort(ms.begin(), ms.end());
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["found_fraction"] = static_cast<double>(found) / static_cast<double>(ms.size());
}

cv::Mat frame_1080p(int t) {
    cv::Mat img(1080, 1920, CV_8UC3);
    cv::randn(img, cv::Scalar(85, 75, 185), cv::Scalar(8, 8, 8));
    const double ang = (-20.0 + t % 20) * M_PI / 180.0;
    const cv::Point2d entry(-40, 600),
        tip(entry.x + 1000 * std::cos(ang), entry.y + 1000 * std::sin(ang));
    cv::line(img, entry, tip, cv::Scalar(50, 48, 52), 80, cv::LINE_AA);
    return img;
}

void BM_KalmanTracker1080p(benchmark::State& state) {
    vision::KalmanToolTrackerParams p;
    p.red_binarised = state.range(0) != 0;
    vision::KalmanToolTracker tracker(p);
    const hal::FrameFormat fmt{1920, 1080, 1920 * 3, hal::PixelFormat::kBgr24};
    tracker.configure(fmt);
    std::vector<cv::Mat> frames;
    for (int t = 0; t < 20; ++t) frames.push_back(frame_1080p(t));
    time_tracking(state, tracker, frames, fmt);
}
BENCHMARK(BM_KalmanTracker1080p)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(3.0);

// The likelihood tracker with the shipped model, on a scope-like frame: black
// surround, red tissue in the lit circle, a grey shaft entering from the rim; with
// Arg 2 a second shaft from the lower right whose tip sweeps across the first one
// (separate, touching, crossing: the two-tool goal).
void BM_LikelihoodTracker1080p(benchmark::State& state) {
    vision::ToolLikelihood model;
    std::string error;
    if (!model.load(std::string(ENDOTOWER_SOURCE_DIR) + "/board/sim/models/tool_likelihood.bin",
                    error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    // range(1) 0: without the bars from the rim (docs/performance.md, their cost).
    vision::LikelihoodToolTrackerParams params;
    params.rim_bars = state.range(1) != 0;
    vision::LikelihoodToolTracker tracker(model, params);
    const hal::FrameFormat fmt{1920, 1080, 1920 * 3, hal::PixelFormat::kBgr24};
    tracker.configure(fmt);
    std::vector<cv::Mat> frames;
    for (int t = 0; t < 20; ++t) {
        cv::Mat img(1080, 1920, CV_8UC3, cv::Scalar(0, 0, 0)), tissue(1080, 1920, CV_8UC3),
            circle(1080, 1920, CV_8U, cv::Scalar(0));
        cv::randn(tissue, cv::Scalar(60, 50, 190), cv::Scalar(8, 8, 8));
        cv::circle(circle, {960, 540}, 520, cv::Scalar(255), -1);
        tissue.copyTo(img, circle);
        const double ang = (-20.0 + t) * M_PI / 180.0;
        const cv::Point2d entry(400, 700),
            tip(entry.x + 700 * std::cos(ang), entry.y + 700 * std::sin(ang));
        cv::Mat bar(1080, 1920, CV_8U, cv::Scalar(0));
        cv::line(bar, entry - (tip - entry), tip, cv::Scalar(255), 60, cv::LINE_AA);
        if (state.range(0) == 2) {
            const cv::Point2d entry2(1500, 900), tip2(1100 - 12 * t, 520 - 4 * t);
            cv::line(bar, entry2 - (tip2 - entry2), tip2, cv::Scalar(255), 44, cv::LINE_AA);
        }
        img.setTo(cv::Scalar(128, 126, 124), bar & circle);
        frames.push_back(img);
    }
    time_tracking(state, tracker, frames, fmt);
}
BENCHMARK(BM_LikelihoodTracker1080p)
    ->ArgsProduct({{1, 2}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3.0);

// The book's further trackers (ekf, mog2, particle, particle_sorted, hybrid, mhi) by
// name, on the moving-shaft frames of the Kalman benchmark (motion for mog2/mhi).
void BM_BookTracker1080p(benchmark::State& state) {
    const std::string_view name =
        vision::book_tracker_names()[static_cast<std::size_t>(state.range(0))];
    state.SetLabel(std::string(name));
    const std::unique_ptr<vision::ToolTracker> tracker = vision::make_book_tracker(name);
    const hal::FrameFormat fmt{1920, 1080, 1920 * 3, hal::PixelFormat::kBgr24};
    tracker->configure(fmt);
    std::vector<cv::Mat> frames;
    for (int t = 0; t < 20; ++t) frames.push_back(frame_1080p(t));
    time_tracking(state, *tracker, frames, fmt);
}
BENCHMARK(BM_BookTracker1080p)->DenseRange(0, 5)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The analysis reduction to 320 px wide: PAL 720x576 (factor 2.25) and the sznitman
// clip's 384x288 (1.2), AreaMean's general path against cv::resize INTER_AREA (the same
// bytes: test_block_mean.cpp). Arg: 0 cv::resize, 1 AreaMean; range(1): source width.
void BM_AreaReduction(benchmark::State& state) {
    const int w = static_cast<int>(state.range(1)), h = w * 4 / 5;
    const int dw = 320, dh = static_cast<int>(std::lround(h * 320.0 / w));
    cv::Mat src(h, w, CV_8UC3), dst(dh, dw, CV_8UC3);
    cv::randu(src, 0, 256);
    vision::AreaMean reduce;
    reduce.configure(w, h, dw, dh, 3);
    for (auto _ : state) {
        if (state.range(0) == 0)
            cv::resize(src, dst, dst.size(), 0, 0, cv::INTER_AREA);
        else
            reduce.run(src.data, src.step, dst.data, dst.step);
        benchmark::DoNotOptimize(dst.data);
    }
}
BENCHMARK(BM_AreaReduction)
    ->ArgsProduct({{0, 1}, {384, 720}})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();
