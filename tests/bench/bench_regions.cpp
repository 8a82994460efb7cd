// Region-tracking benchmarks (docs/regions.md, docs/performance.md), median and p99:
//  - propagation: the per-frame cost of keeping a marked region anchored at 1920x1080
//    (LK on the region's points + RANSAC homography), drift correction off, and its heap
//    allocations per frame (allocs_per_frame: operator new; c_allocs_per_frame: the C
//    allocator, where OpenCV's buffers come from);
//  - keyframe matching per descriptor at 640x480 and 1920x1080: in a window around
//    the region (drift correction, while tracked) and over the whole frame (recovery,
//    while lost);
//  - image pairs with ground truth resampled to 640x480 and 1920x1080 (tables 6.3/6.4).
// OpenCV runs single-threaded here, so the CPU column is the whole cost of a call.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <opencv2/core/persistence.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "alloc_counter.hpp"
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
        cv::Mat m =
            cv::getRotationMatrix2D(cv::Point2f(s.width / 2.f, s.height / 2.f), 0.2 * i, 1.0);
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
    state.counters["tracked_fraction"] =
        static_cast<double>(tracked) / static_cast<double>(ms.size());
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
    std::int64_t allocs = 0, c_allocs = 0;
    for (auto _ : state) {
        const std::size_t k = i % 38, index = k < 20 ? k : 38 - k;
        hal::Frame f = view(frames[index], i++);
        // Counted around track() only: the benchmark library and `ms` allocate between.
        const std::int64_t a0 = bench::allocations(), c0 = bench::c_allocations();
        const auto t0 = std::chrono::steady_clock::now();
        tracker.track(f, out);
        const auto t1 = std::chrono::steady_clock::now();
        allocs += bench::allocations() - a0;
        c_allocs += bench::c_allocations() - c0;
        ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        tracked += out[0].state == vision::RegionState::kTracked && !out[0].keyframe_match;
    }
    const auto n = static_cast<double>(ms.size());
    state.counters["allocs_per_frame"] = static_cast<double>(allocs) / n;
    state.counters["c_allocs_per_frame"] = static_cast<double>(c_allocs) / n;
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
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        tracked += out[0].state == vision::RegionState::kTracked;
    }
    report(state, ms, tracked);
    state.SetLabel(std::string(vision::to_string(descriptor)) +
                   (whole ? " whole frame" : " near the region"));
}
BENCHMARK(BM_RegionKeyframe)
    ->ArgsProduct({{0, 1, 2}, {480, 1080}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// Image pairs with ground-truth homographies (../shared/data), resampled to 640x480 or
// 1920x1080 like the book's tables 6.3/6.4: the time to locate the region in the
// second image (keyframe matching) and its mean corner error against the truth.
// range(0): pair; range(1): descriptor; range(2): height.
struct Pair {
    const char *name, *a, *b, *h;
    bool h_maps_b_to_a;
};
constexpr Pair kPairs[] = {
    {"graf1-graf3", "opencv_samples/graf1.png", "opencv_samples/graf3.png",
     "opencv_samples/H1to3p.xml", false},
    {"graf", "homography_pairs/grafA.png", "homography_pairs/grafB.png",
     "homography_pairs/graf_model.txt", true},
    {"boat", "homography_pairs/boatA.png", "homography_pairs/boatB.png",
     "homography_pairs/boat_model.txt", true},
    {"adam", "homography_pairs/adamA.png", "homography_pairs/adamB.png",
     "homography_pairs/adam_model.txt", true},
};

bool load_h(const std::string& path, cv::Matx33d& h) {
    if (path.ends_with(".xml")) {
        cv::Mat m;
        cv::FileStorage(path, cv::FileStorage::READ)["H13"] >> m;
        if (m.empty()) return false;
        h = cv::Matx33d(m);
        return true;
    }
    std::ifstream in(path);
    for (int i = 0; i < 9; ++i)
        if (!(in >> h.val[i])) return false;
    return true;
}

// Pixel-centre scaling from `from` to `to`: x' = s x + (s - 1) / 2.
cv::Matx33d scaling(cv::Size from, cv::Size to) {
    const double sx = static_cast<double>(to.width) / from.width,
                 sy = static_cast<double>(to.height) / from.height;
    return {sx, 0, (sx - 1) / 2, 0, sy, (sy - 1) / 2, 0, 0, 1};
}

void BM_RegionPair(benchmark::State& state) {
    const Pair& pair = kPairs[state.range(0)];
    const auto descriptor = static_cast<vision::RegionDescriptor>(state.range(1));
    const cv::Size size = state.range(2) == 480 ? cv::Size(640, 480) : cv::Size(1920, 1080);
    const std::string data = std::string(ENDOTOWER_SOURCE_DIR) + "/../shared/data/";
    cv::Mat a0 = cv::imread(data + pair.a, cv::IMREAD_COLOR),
            b0 = cv::imread(data + pair.b, cv::IMREAD_COLOR);
    cv::Matx33d h;  // A -> B
    if (a0.empty() || b0.empty() || !load_h(data + pair.h, h)) {
        state.SkipWithError("needs ../shared/data (opencv_samples, homography_pairs): absent");
        return;
    }
    if (pair.h_maps_b_to_a) h = h.inv();
    cv::Mat a, b;
    cv::resize(a0, a, size, 0, 0, cv::INTER_AREA);
    cv::resize(b0, b, size, 0, 0, size.width > b0.cols ? cv::INTER_CUBIC : cv::INTER_AREA);
    const cv::Matx33d truth = scaling(b0.size(), size) * h * scaling(a0.size(), size).inv();
    // The middle of A, 40 % of each side: in view in B for every pair.
    const double w = size.width, hh = size.height;
    const std::vector<vision::Point2> region{
        {0.3 * w, 0.3 * hh}, {0.7 * w, 0.3 * hh}, {0.7 * w, 0.7 * hh}, {0.3 * w, 0.7 * hh}};
    std::vector<double> ms;
    double error_sum = 0;
    std::size_t tracked = 0, i = 0;
    for (auto _ : state) {
        vision::RegionTracker tracker({.descriptor = descriptor});
        std::string error;
        if (!tracker.mark(0, region, view(a, 2 * i), error)) {
            state.SkipWithError(error.c_str());
            return;
        }
        std::array<vision::RegionEstimate, 1> out{};
        hal::Frame f = view(b, 2 * i + 1);
        ++i;
        const auto t0 = std::chrono::steady_clock::now();
        tracker.track(f, out);
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        if (out[0].state != vision::RegionState::kTracked) continue;
        ++tracked;
        double e = 0;
        for (std::size_t v = 0; v < region.size(); ++v) {
            const cv::Vec3d q = truth * cv::Vec3d(region[v].x, region[v].y, 1);
            e += std::hypot(out[0].polygon[v].x - q[0] / q[2], out[0].polygon[v].y - q[1] / q[2]) /
                 4;
        }
        error_sum += e;
    }
    report(state, ms, tracked);
    state.counters["corner_error_px"] = tracked > 0 ? error_sum / static_cast<double>(tracked) : -1;
    state.SetLabel(std::string(pair.name) + " " + std::string(vision::to_string(descriptor)));
}
BENCHMARK(BM_RegionPair)
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2}, {480, 1080}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

}  // namespace

// One OpenCV thread: the CPU column is then the whole cost of a call, whatever else
// the machine is running (the analysis thread shares the board's cores anyway).
int main(int argc, char** argv) {
    cv::setNumThreads(1);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
