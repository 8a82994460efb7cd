// Deterministic-clock tests of the fixed-latency scheduler and its fail-safe.
#include <gtest/gtest.h>

#include <thread>

#include "endotower/app/pipeline.hpp"
#include "endotower/app/trace_reader.hpp"
#include "fakes.hpp"

namespace endotower::test {
namespace {

constexpr hal::Nanos kPeriod = 16'666'667;  // 60 fps

class CollectTrace final : public app::TraceSink {
public:
    void write(std::string_view l) override {
        app::TraceRecord r;
        std::string err;
        ASSERT_TRUE(app::parse_trace_line(std::string(l), r, err)) << err << "\n" << l;
        records.push_back(r);
    }
    std::vector<app::TraceRecord> records;
};

class SilentLog final : public app::Log {
public:
    void write(app::LogLevel, std::string_view m) override { lines.emplace_back(m); }
    std::vector<std::string> lines;
};

struct Rig {
    explicit Rig(int frames, int buffers = 6) : source(clock, frames, kPeriod, 64, 48, buffers), sink(clock) {}
    app::PipelineSummary run(app::PipelineConfig cfg, app::AnalysisStage* stage,
                             hal::ControlInput* input = nullptr) {
        app::Pipeline p(cfg, source, sink, clock, input, stage, &trace, log);
        return p.run();
    }
    ManualClock clock;
    FakeSource source;
    RecordingSink sink;
    CollectTrace trace;
    SilentLog log;
};

// Every frame out, in order, none repeated, each exactly `latency` after capture.
void expect_fixed_latency(const Rig& rig, int frames, hal::Nanos latency) {
    ASSERT_EQ(rig.sink.shown.size(), static_cast<std::size_t>(frames));
    for (int i = 0; i < frames; ++i) {
        const Shown& s = rig.sink.shown[static_cast<std::size_t>(i)];
        EXPECT_EQ(s.sequence, static_cast<std::uint64_t>(i));
        EXPECT_EQ(s.first_byte, FakeSource::fill_value(i)) << "frame " << i << " shows another frame's pixels";
        EXPECT_EQ(s.presented_ns - s.capture_ns, latency) << "frame " << i;
    }
    EXPECT_EQ(rig.source.outstanding(), 0);
}

TEST(Pipeline, DefaultLatencyIsOneFramePeriodForEveryFrame) {
    Rig rig(120);
    ScriptedStage stage;
    const auto s = rig.run({}, &stage);
    EXPECT_TRUE(s.ok) << s.error;
    expect_fixed_latency(rig, 120, kPeriod);
    EXPECT_EQ(s.latency_min_ns, kPeriod);
    EXPECT_EQ(s.latency_max_ns, kPeriod);
    EXPECT_EQ(s.late_frames, 0);
    EXPECT_EQ(s.passthrough_frames, 0);
    // Default virtual cost is half a period: every frame is analysed and its own
    // result is ready at compose time (period - 4 ms), so the overlay is never old.
    EXPECT_EQ(s.analysed_frames, 120);
    for (const auto& r : rig.trace.records) {
        ASSERT_TRUE(r.analysis_age.has_value()) << "frame " << r.frame;
        EXPECT_EQ(*r.analysis_age, 0);
        EXPECT_EQ(r.latency_ns, kPeriod);
    }
}

TEST(Pipeline, ConfiguredLatencyOfSeveralPeriodsHolds) {
    for (hal::Nanos latency : {2 * kPeriod, 3 * kPeriod / 2, 5 * kPeriod / 2}) {
        Rig rig(90);
        app::PipelineConfig cfg;
        cfg.latency_ns = latency;
        const auto s = rig.run(cfg, nullptr);
        EXPECT_TRUE(s.ok);
        expect_fixed_latency(rig, 90, latency);
        EXPECT_EQ(s.late_frames, 0) << "latency " << latency;
    }
}

TEST(Pipeline, SlowAnalysisAgesTheOverlayButNotTheVideo) {
    Rig rig(60);
    ScriptedStage stage;
    stage.cost_ns = 3 * kPeriod;  // each call costs three frames of virtual time
    const auto s = rig.run({}, &stage);
    expect_fixed_latency(rig, 60, kPeriod);
    // Busy for 3 periods after each submit: frames 0, 3, 6, ... are analysed.
    const std::vector<int> seen = stage.seen_frames();
    ASSERT_EQ(seen.size(), 20u);
    for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], static_cast<int>(3 * i));
    // Frame 3k+j (j=0,1,2) is composed at capture + period - 4 ms; the result of
    // frame 3k becomes ready at capture(3k) + 3 periods, i.e. in time for frame
    // 3k+3 only: the newest shown result is from 3(k-1), age 3 + j.
    for (const auto& r : rig.trace.records) {
        if (r.frame < 3) {
            EXPECT_FALSE(r.analysis_age.has_value()) << r.frame;
            continue;
        }
        ASSERT_TRUE(r.analysis_age.has_value()) << r.frame;
        EXPECT_EQ(*r.analysis_age, 3 + r.frame % 3) << r.frame;
        // max_overlay_age 3: older results are withheld, reported as stale.
        EXPECT_EQ(r.passthrough, *r.analysis_age > 3) << r.frame;
    }
}

TEST(Pipeline, ThrowingStageGivesPassthroughThenRecovers) {
    Rig rig(40);
    ScriptedStage stage;
    stage.script = [](int f) { return f >= 10 && f < 20 ? ScriptedStage::Act::kThrow : ScriptedStage::Act::kOk; };
    const auto s = rig.run({}, &stage);
    expect_fixed_latency(rig, 40, kPeriod);
    EXPECT_EQ(s.faults, 1);
    for (const auto& r : rig.trace.records) {
        const bool failing = r.frame >= 10 && r.frame < 20;
        EXPECT_EQ(r.passthrough, failing) << r.frame;
        EXPECT_EQ(r.fault.value_or(""), failing ? "analysis_threw" : "") << r.frame;
        EXPECT_EQ(rig.sink.shown[static_cast<std::size_t>(r.frame)].had_overlay, !failing) << r.frame;
    }
}

TEST(Pipeline, OutOfMemoryInAnalysisIsContained) {
    Rig rig(30);
    ScriptedStage stage;
    stage.script = [](int f) { return f == 5 ? ScriptedStage::Act::kBadAlloc : ScriptedStage::Act::kOk; };
    const auto s = rig.run({}, &stage);
    expect_fixed_latency(rig, 30, kPeriod);
    EXPECT_EQ(rig.trace.records[5].fault.value_or(""), "analysis_out_of_memory");
    EXPECT_TRUE(rig.trace.records[5].passthrough);
    EXPECT_FALSE(rig.trace.records[6].passthrough);
    EXPECT_EQ(s.faults, 1);
}

TEST(Pipeline, HungStageNeverStopsTheVideo) {
    Rig rig(60);
    ScriptedStage stage;
    stage.script = [](int f) { return f == 10 ? ScriptedStage::Act::kHang : ScriptedStage::Act::kOk; };
    app::PipelineConfig cfg;
    cfg.analysis_wall_timeout_ns = 50 * hal::kMillisecond;
    // The video runs on virtual time, far faster than the wall-clock watchdog: let
    // the stage return when frame 30 is shown, and give its thread time to finish.
    rig.sink.on_present = [&](std::uint64_t seq) {
        if (seq != 30) return;
        const int before = stage.finished.load();
        stage.release_hang();
        while (stage.finished.load() == before) std::this_thread::yield();
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    };
    const auto s = rig.run(cfg, &stage);
    expect_fixed_latency(rig, 60, kPeriod);
    EXPECT_GE(s.faults, 1);
    int hung = 0;
    for (const auto& r : rig.trace.records) {
        if (r.frame < 10) {
            EXPECT_FALSE(r.passthrough) << r.frame;
        }
        if (r.fault == "analysis_hung") {
            ++hung;
            EXPECT_TRUE(r.passthrough);
        }
    }
    EXPECT_GE(hung, 1);
    // After the hang, analysis resumed: the last frames carry a fresh overlay.
    EXPECT_FALSE(rig.trace.records.back().passthrough);
    EXPECT_EQ(rig.trace.records.back().analysis_age.value_or(-1), 0);
}

TEST(Pipeline, QueueIsBoundedByTheSourcePool) {
    // A latency of 4 periods wants 5 frames in flight; with a pool of 3 only 2 can
    // wait (one buffer stays with the source). Capture waits for the oldest to be
    // shown at its due time: the latency holds, nothing is dropped or reordered, and
    // the pipeline warns that a live source would drop frames.
    Rig rig(30, 3);
    app::PipelineConfig cfg;
    cfg.latency_ns = 4 * kPeriod;
    const auto s = rig.run(cfg, nullptr);
    expect_fixed_latency(rig, 30, 4 * kPeriod);
    EXPECT_EQ(s.frames_out, 30);
    EXPECT_EQ(s.late_frames, 0);
    ASSERT_FALSE(rig.log.lines.empty());
    EXPECT_NE(rig.log.lines[0].find("needs 6 capture buffers, the source has 3"), std::string::npos)
        << rig.log.lines[0];
}

TEST(Pipeline, FormatChangeReconfiguresWithoutStopping) {
    Rig rig(40);
    rig.source.change_size_at(20, 32, 24);
    ScriptedStage stage;
    const auto s = rig.run({}, &stage);
    EXPECT_TRUE(s.ok) << s.error;
    expect_fixed_latency(rig, 40, kPeriod);
    EXPECT_EQ(s.format_changes, 1);
    ASSERT_EQ(rig.sink.formats.size(), 2u);
    EXPECT_EQ(rig.sink.formats[1].width, 32);
    EXPECT_EQ(stage.configured, (std::vector<int>{64, 32}));
    for (const auto& r : rig.trace.records) {
        EXPECT_EQ(r.format_change.has_value(), r.frame == 20) << r.frame;
        EXPECT_EQ(rig.sink.shown[static_cast<std::size_t>(r.frame)].width, r.frame < 20 ? 64 : 32);
    }
    EXPECT_EQ(rig.trace.records[20].format_change->width, 32);
    EXPECT_EQ(rig.trace.records[20].format_change->pixel_format, "bgr24");
    // The overlay resumes on the new size.
    EXPECT_TRUE(rig.sink.shown.back().had_overlay);
}

class ListInput final : public hal::ControlInput {
public:
    ListInput(hal::Clock& c, std::vector<hal::ControlEvent> e) : clock_(c), events_(std::move(e)) {}
    bool poll(hal::ControlEvent& out) override {
        if (i_ == events_.size() || events_[i_].time_ns > clock_.now()) return false;
        out = events_[i_++];
        return true;
    }

private:
    hal::Clock& clock_;
    std::vector<hal::ControlEvent> events_;
    std::size_t i_ = 0;
};

TEST(Pipeline, ControlEventsReachTheStageAndTheTraceAtTheirFrame) {
    Rig rig(20);
    const hal::Nanos t0 = rig.clock.now();
    using K = hal::ControlEvent::Kind;
    ListInput input(rig.clock, {{K::kButtonPress, 0, 0, t0 + 5 * kPeriod},
                                {K::kWheel, 0, -2, t0 + 5 * kPeriod + 1000},
                                {K::kButtonRelease, 0, 0, t0 + 9 * kPeriod - 1}});
    ScriptedStage stage;
    rig.run({}, &stage, &input);
    // An event is polled with the first frame captured at or after it.
    ASSERT_EQ(rig.trace.records[5].input.size(), 1u);
    EXPECT_EQ(rig.trace.records[5].input[0].kind, "press");
    ASSERT_EQ(rig.trace.records[6].input.size(), 1u);
    EXPECT_EQ(rig.trace.records[6].input[0].kind, "wheel");
    EXPECT_EQ(rig.trace.records[6].input[0].delta, -2);
    ASSERT_EQ(rig.trace.records[9].input.size(), 1u);
    EXPECT_EQ(rig.trace.records[9].input[0].kind, "release");
    EXPECT_EQ(rig.trace.records[9].input[0].t_ns, t0 + 9 * kPeriod - 1);
    ASSERT_EQ(stage.events.size(), 3u);
    EXPECT_EQ(stage.events[1].delta, -2);
}

TEST(Pipeline, StageTraceMembersAreSplicedIntoTheFrameLine) {
    Rig rig(10);
    ScriptedStage stage;
    rig.run({}, &stage);
    for (const auto& r : rig.trace.records) {
        EXPECT_EQ(r.extra, "{\"scripted_frame\":" + std::to_string(r.frame) + "}");
        EXPECT_TRUE(r.stages_us.count("analysis"));
        EXPECT_TRUE(r.stages_us.count("present"));
    }
}

}  // namespace
}  // namespace endotower::test
