// Tool-gesture benchmark (issue 6, docs/performance.md): segmentation + the features
// + classification for one 1920x1080 frame with two tools (fig. 3.12e-h, rendered by
// the scene simulator), with the shipped models; median and p99 per frame, heap
// allocations per frame (operator new, and the C allocator, which OpenCV's buffers
// come from; every thread), CPU time of the whole process (OpenCV's worker threads too).
// ENDOTOWER_GESTURE_MODEL=FILE benchmarks another gesture model (e.g. a profile one).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <vector>

#include "alloc_counter.hpp"
#include "c_alloc_counter.hpp"
#include "endotower/scene/renderer.hpp"
#include "endotower/vision/gesture_classifier.hpp"
#include "endotower/vision/gesture_segmenter.hpp"

namespace {

using namespace endotower;

void BM_Gestures1080pTwoTools(benchmark::State& state) {
    const std::string root = ENDOTOWER_SOURCE_DIR;
    std::string error;
    vision::ToolLikelihood tool_model;
    vision::GestureClassifier classifier;
    scene::Scenario scenario;
    if (!tool_model.load(root + "/board/sim/models/tool_likelihood.bin", error) ||
        !classifier.load(std::getenv("ENDOTOWER_GESTURE_MODEL") != nullptr
                             ? std::getenv("ENDOTOWER_GESTURE_MODEL")
                             : root + "/board/sim/models/gestures.yml",
                         error) ||
        !scene::load_scenario(root + "/board/sim/scenarios/fig312_nonoverlapping.yaml", scenario,
                              error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    scenario.width = 1920;
    scenario.height = 1080;
    scene::SceneRenderer renderer;
    if (!renderer.init(scenario, 312, error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    std::vector<scene::Image> frames(4);
    for (int i = 0; i < 4; ++i) {
        scene::FrameTruth truth;
        renderer.render(i * 4, frames[i], truth);
    }
    vision::GestureSegmenterParams p;
    p.method = classifier.segmentation();
    p.profile = classifier.features() == vision::GestureFeatureSet::kProfile;
    vision::GestureSegmenter segmenter(&tool_model, p);
    const hal::FrameFormat fmt{1920, 1080, 1920 * 3, hal::PixelFormat::kBgr24};
    segmenter.configure(fmt);
    std::array<vision::GestureBlob, vision::GestureSegmenter::kMaxBlobs> blobs{};
    std::vector<double> ms;
    ms.reserve(100000);
    std::size_t i = 0, found = 0;
    std::int64_t allocs = 0, c_allocs = 0;
    for (auto _ : state) {
        hal::Frame f;
        f.format = fmt;
        f.data = frames[i++ % frames.size()].bgr.data();
        const std::int64_t a0 = bench::allocations(), c0 = bench::c_allocations();
        const auto t0 = std::chrono::steady_clock::now();
        const std::size_t n = segmenter.segment(f, blobs);
        for (std::size_t b = 0; b < n; ++b)
            found += classifier.classify(blobs[b].features, blobs[b].entries).label >= 0;
        const auto t1 = std::chrono::steady_clock::now();
        allocs += bench::allocations() - a0;
        c_allocs += bench::c_allocations() - c0;
        ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    const double count = static_cast<double>(ms.size());
    state.counters["allocs_per_frame"] = static_cast<double>(allocs) / count;
    state.counters["c_allocs_per_frame"] = static_cast<double>(c_allocs) / count;
    state.counters["tools_per_frame"] = static_cast<double>(found) / count;
}
BENCHMARK(BM_Gestures1080pTwoTools)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3.0)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
