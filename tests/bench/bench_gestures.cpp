// Tool-gesture benchmark (issue 6, docs/performance.md): segmentation + the features
// + classification for one 1920x1080 frame with two tools (fig. 3.12e-h, rendered by
// the scene simulator), with the shipped models; median and p99 per frame, heap
// allocations per frame (operator new, and the C allocator, which OpenCV's buffers
// come from; every thread), CPU time of the whole process (OpenCV's worker threads too).
// Arg `threads`: 2 (the shipped segmenter: a helper thread takes half of the per-pixel
// passes and shares the regions) or 1 (all on the calling thread); compare them
// side by side with --benchmark_enable_random_interleaving=true (docs/performance.md).
// ENDOTOWER_GESTURE_MODEL=FILE benchmarks another gesture model (e.g. a profile one).
// `--frames N` runs N frames without the benchmark and prints a checksum (run_frames).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "endotower/scene/renderer.hpp"
#include "endotower/vision/gesture_classifier.hpp"
#include "endotower/vision/gesture_segmenter.hpp"

namespace {

using namespace endotower;

// The benchmark's models and its four rendered frames (fig. 3.12e-h at 1920x1080).
struct GestureFrames {
    vision::ToolLikelihood tool_model;
    vision::GestureClassifier classifier;
    std::vector<scene::Image> frames = std::vector<scene::Image>(4);
    std::unique_ptr<vision::GestureSegmenter> segmenter;
    const hal::FrameFormat fmt{1920, 1080, 1920 * 3, hal::PixelFormat::kBgr24};

    bool init(std::string& error, int threads = 2) {
        const std::string root = ENDOTOWER_SOURCE_DIR;
        scene::Scenario scenario;
        const char* model = std::getenv("ENDOTOWER_GESTURE_MODEL");
        if (!tool_model.load(root + "/board/sim/models/gesture_tool_likelihood.bin", error) ||
            !classifier.load(model != nullptr ? model : root + "/board/sim/models/gestures.yml",
                             error) ||
            !scene::load_scenario(root + "/board/sim/scenarios/fig312_nonoverlapping.yaml",
                                  scenario, error))
            return false;
        scenario.width = 1920;
        scenario.height = 1080;
        scene::SceneRenderer renderer;
        if (!renderer.init(scenario, 312, error)) return false;
        for (int i = 0; i < 4; ++i) {
            scene::FrameTruth truth;
            renderer.render(i * 4, frames[i], truth);
        }
        vision::GestureSegmenterParams p = classifier.segmenter_params();
        p.threads = threads;
        segmenter = std::make_unique<vision::GestureSegmenter>(&tool_model, p);
        segmenter->configure(fmt);
        return true;
    }
    hal::Frame frame(std::size_t i) {
        hal::Frame f;
        f.format = fmt;
        f.data = frames[i % frames.size()].bgr.data();
        return f;
    }
};

void BM_Gestures1080pTwoTools(benchmark::State& state) {
    std::string error;
    GestureFrames g;
    if (!g.init(error, static_cast<int>(state.range(0)))) {
        state.SkipWithError(error.c_str());
        return;
    }
    vision::GestureSegmenter& segmenter = *g.segmenter;
    const vision::GestureClassifier& classifier = g.classifier;
    std::array<vision::GestureBlob, vision::GestureSegmenter::kMaxBlobs> blobs{};
    std::vector<double> ms;
    ms.reserve(100000);
    std::size_t i = 0, found = 0;
    std::int64_t allocs = 0, c_allocs = 0;
    for (auto _ : state) {
        const hal::Frame f = g.frame(i++);
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
    ->ArgName("threads")
    ->Arg(2)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3.0)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// `--frames N`: N frames in turn instead of the benchmark, then a checksum (FNV-1a) of
// what the first four gave: the mask, each region's tip, radius, arms, features and label.
// A change that must not change the output leaves it as it was; under callgrind it counts
// the instructions per frame (docs/performance.md).
int run_frames(int n) {
    std::string error;
    GestureFrames g;
    if (!g.init(error)) {
        std::fprintf(stderr, "bench_gestures: %s\n", error.c_str());
        return 1;
    }
    std::uint64_t sum = 1469598103934665603ull;
    auto mix = [&sum](const void* data, std::size_t size) {
        for (std::size_t i = 0; i < size; ++i)
            sum = (sum ^ static_cast<const unsigned char*>(data)[i]) * 1099511628211ull;
    };
    std::array<vision::GestureBlob, vision::GestureSegmenter::kMaxBlobs> blobs{};
    for (int i = 0; i < n; ++i) {
        const std::size_t found = g.segmenter->segment(g.frame(static_cast<std::size_t>(i)), blobs);
        for (std::size_t b = 0; b < found; ++b) {
            const int label = g.classifier.classify(blobs[b].features, blobs[b].entries).label;
            if (i >= 4) continue;
            const auto v = blobs[b].features.as_vector();
            mix(&label, sizeof label);
            mix(&blobs[b].tip, sizeof blobs[b].tip);
            mix(&blobs[b].radius_px, sizeof blobs[b].radius_px);
            mix(&blobs[b].arms, sizeof blobs[b].arms);
            mix(v.data(), sizeof(float) * v.size());
        }
        if (i < 4) {
            mix(&found, sizeof found);
            const auto mask = g.segmenter->mask();
            mix(mask.data(), mask.size());
        }
    }
    std::printf("%d frames, checksum %016llx\n", n, static_cast<unsigned long long>(sum));
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc >= 2 && std::string(argv[1]) == "--frames") {
        char* end = nullptr;
        const long n = argc == 3 ? std::strtol(argv[2], &end, 10) : 0;
        if (argc != 3 || *end != 0 || n < 1 || n > 1000000) {
            std::fprintf(stderr, "bench_gestures: --frames needs a whole number in 1..1000000\n");
            return 2;
        }
        return run_frames(static_cast<int>(n));
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
