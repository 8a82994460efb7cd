// Strip-marker benchmark (issue 6, docs/performance.md, docs/markers.md): one
// StripMarkerTracker call (segmentation, blob analysis, silhouettes) on the tables
// 3.1/3.2 frames (board/sim/scenarios/t31_t32_marker_points.yaml) at 640x480 and
// 1920x1080; median and p99 per frame, and the markers found per frame.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "endotower/scene/renderer.hpp"
#include "endotower/vision/strip_marker_tracker.hpp"

namespace {

using namespace endotower;

void BM_StripMarkers(benchmark::State& state) {
    const int width = static_cast<int>(state.range(0)), height = static_cast<int>(state.range(1));
    std::string error;
    scene::Scenario scenario;
    if (!scene::load_scenario(
            std::string(ENDOTOWER_SOURCE_DIR) + "/board/sim/scenarios/t31_t32_marker_points.yaml",
            scenario, error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    scenario.width = width;
    scenario.height = height;
    scene::SceneRenderer renderer;
    if (!renderer.init(scenario, scenario.seed, error)) {
        state.SkipWithError(error.c_str());
        return;
    }
    std::vector<scene::Image> frames(4);
    for (int i = 0; i < 4; ++i) {
        scene::FrameTruth truth;
        renderer.render(8 + i * 6, frames[i], truth);  // 50-70 mm
    }
    const hal::FrameFormat fmt{width, height, width * 3, hal::PixelFormat::kBgr24};
    vision::StripMarkerTracker tracker;
    tracker.configure(fmt);
    std::array<vision::StripMarker, vision::StripMarkerTracker::kMaxMarkers> out{};
    std::vector<double> ms;
    ms.reserve(100000);
    std::size_t i = 0, found = 0;
    for (auto _ : state) {
        hal::Frame f;
        f.format = fmt;
        f.data = frames[i++ % frames.size()].bgr.data();
        const auto t0 = std::chrono::steady_clock::now();
        found += tracker.track(f, out);
        ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
    }
    std::sort(ms.begin(), ms.end());
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["markers_per_frame"] =
        static_cast<double>(found) / static_cast<double>(ms.size());
}
BENCHMARK(BM_StripMarkers)
    ->Args({640, 480})
    ->Args({1920, 1080})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
