// Video-path benchmarks at 1920x1080 (docs/performance.md):
//  - Compose: capture buffer -> CPU blend of an overlay covering 10 % -> sink buffer;
//  - Pipeline: the whole fixed-latency pipeline, in-memory 1080p source, the
//    status-badge analysis stage, compose into a sink buffer, virtual clock;
//  - ReplayBundled: `endotower sim`'s path on the bundled recording (decode, analyse,
//    compose, mp4v encode: the README's command 1), as a real-time factor.
// Each reports median and p99 per frame (ms) and heap allocations per frame in
// steady state, counted over every thread.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <vector>

#include "alloc_counter.hpp"
#include "endotower/app/pipeline.hpp"
#include "endotower/app/status_badge.hpp"
#include "endotower/sim/compositor.hpp"
#include "endotower/sim/file_sink.hpp"
#include "endotower/sim/recorded_source.hpp"
#include "endotower/sim/virtual_clock.hpp"
#include "fakes.hpp"

namespace {

using namespace endotower;
constexpr int kW = 1920, kH = 1080;

// A menu-like overlay over 10 % of the frame: a translucent panel with opaque
// text-like strokes and anti-aliased (partial alpha) edges.
void make_overlay(std::vector<std::uint8_t>& px, hal::OverlayLayer& layer) {
    px.assign(static_cast<std::size_t>(kW) * kH * 4, 0);
    layer.width = kW;
    layer.height = kH;
    layer.stride = kW * 4;
    layer.rgba = px.data();
    const hal::Rect panel{1200, 700, 640, 324};  // 207,360 px = 10.0 % of 2,073,600
    for (int y = panel.y; y < panel.y + panel.height; ++y)
        for (int x = panel.x; x < panel.x + panel.width; ++x) {
            std::uint8_t* p = &px[(static_cast<std::size_t>(y) * kW + x) * 4];
            const bool stroke = (y / 6) % 5 == 0 && (x / 4) % 3 != 0;
            const bool edge = ((x + y) % 17) == 0;
            p[0] = stroke ? 255 : 30;
            p[1] = stroke ? 255 : 60;
            p[2] = stroke ? 255 : 90;
            p[3] = stroke ? 255 : edge ? 96 : 160;
        }
    layer.rects[0] = panel;
    layer.rect_count = 1;
}

void report(benchmark::State& state, std::vector<double>& ms, std::int64_t allocs, std::int64_t frames) {
    std::sort(ms.begin(), ms.end());
    if (ms.empty()) return;
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["allocs_per_frame"] = frames > 0 ? static_cast<double>(allocs) / static_cast<double>(frames) : 0.0;
}

void BM_Compose1080p(benchmark::State& state) {
    std::vector<std::uint8_t> video(static_cast<std::size_t>(kW) * kH * 3), out(video.size());
    for (std::size_t i = 0; i < video.size(); ++i) video[i] = static_cast<std::uint8_t>(i * 31 + 7);
    std::vector<std::uint8_t> ov;
    hal::OverlayLayer layer;
    make_overlay(ov, layer);
    hal::Frame f;
    f.format = {kW, kH, kW * 3, hal::PixelFormat::kBgr24};
    f.data = video.data();
    std::vector<double> ms;
    ms.reserve(100000);
    const std::int64_t a0 = bench::allocations();
    std::int64_t frames = 0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        sim::compose(f, &layer, out.data(), kW * 3);
        benchmark::DoNotOptimize(out.data());
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        ++frames;
    }
    report(state, ms, bench::allocations() - a0, frames);
}
BENCHMARK(BM_Compose1080p)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// Composes into its own buffer like the file sink, without encoding.
class ComposeSink final : public hal::VideoSink {
public:
    explicit ComposeSink(hal::Clock& c) : clock_(c) {}
    bool configure(const hal::FrameFormat& f) override {
        buf_.assign(f.size_bytes(), 0);
        stride_ = f.stride;
        return true;
    }
    hal::Nanos present(const hal::Frame& v, const hal::OverlayLayer* o, hal::Nanos due) override {
        const auto t0 = std::chrono::steady_clock::now();
        sim::compose(v, o, buf_.data(), stride_);
        if (times.size() < times.capacity())
            times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        if (clock_.now() < due) clock_.sleep_until(due);
        return clock_.now();
    }
    bool finish() override { return true; }
    const std::string& error() const override { return err_; }
    std::vector<double> times;

private:
    hal::Clock& clock_;
    std::vector<std::uint8_t> buf_;
    int stride_ = 0;
    std::string err_;
};

// Counts allocations after a warm-up: wraps a stage and snapshots the counter.
class WarmupProbe final : public hal::VideoSink {
public:
    WarmupProbe(hal::VideoSink& inner, int warmup) : inner_(inner), warmup_(warmup) {}
    bool configure(const hal::FrameFormat& f) override { return inner_.configure(f); }
    hal::Nanos present(const hal::Frame& v, const hal::OverlayLayer* o, hal::Nanos due) override {
        if (++n_ == warmup_) start_allocs = bench::allocations();
        return inner_.present(v, o, due);
    }
    bool finish() override {
        end_allocs = bench::allocations();
        return inner_.finish();
    }
    const std::string& error() const override { return inner_.error(); }
    std::int64_t start_allocs = 0, end_allocs = 0;
    int frames_after_warmup() const { return n_ - warmup_; }

private:
    hal::VideoSink& inner_;
    int warmup_, n_ = 0;
};

class QuietLog final : public app::Log {
public:
    void write(app::LogLevel, std::string_view) override {}
};

void BM_Pipeline1080p(benchmark::State& state) {
    const int frames = 600;
    for (auto _ : state) {
        sim::VirtualClock clock;
        test::FakeSource source(clock, frames, 16'666'667, kW, kH, 6);
        ComposeSink sink(clock);
        sink.times.reserve(frames);
        WarmupProbe probe(sink, 60);
        app::StatusBadge badge;
        QuietLog log;
        app::Pipeline p({}, source, probe, clock, nullptr, &badge, nullptr, log);
        const auto s = p.run();
        state.counters["frames_out"] = static_cast<double>(s.frames_out);
        state.counters["analysed"] = static_cast<double>(s.analysed_frames);
        const double fps = s.wall_seconds > 0 ? static_cast<double>(s.frames_out) / s.wall_seconds : 0;
        state.counters["replay_fps"] = fps;
        report(state, sink.times, probe.end_allocs - probe.start_allocs, probe.frames_after_warmup());
    }
}
BENCHMARK(BM_Pipeline1080p)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_ReplayBundled(benchmark::State& state) {
    const std::string input = ENDOTOWER_SOURCE_DIR "/board/sim/media/endotip_rotation.mp4";
    const std::string out = (std::filesystem::temp_directory_path() / "endotower_bench_replay.mp4").string();
    for (auto _ : state) {
        sim::VirtualClock clock;
        sim::RecordedFrameSource source({input, 0.0, 6}, clock);
        if (!source.open()) {
            state.SkipWithError(source.error().c_str());
            return;
        }
        sim::FileSink sink({out, "", source.frame_rate()}, clock);
        app::StatusBadge badge;
        QuietLog log;
        app::Pipeline p({}, source, sink, clock, nullptr, &badge, nullptr, log);
        const auto s = p.run();
        state.counters["frames"] = static_cast<double>(s.frames_out);
        state.counters["x_realtime"] = static_cast<double>(s.media_duration_ns) / 1e9 / s.wall_seconds;
    }
    std::filesystem::remove(out);
}
BENCHMARK(BM_ReplayBundled)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
