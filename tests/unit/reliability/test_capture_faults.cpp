// Fault injection during a replay (issue 10, docs/reliability.md): capture faults from
// sim::FaultInjectingSource under the firmware's NoSignalSource, and a flood of handle
// events, through the real pipeline, status-badge analysis and trace, on a virtual
// clock. Each case asserts: every frame that reached the pipeline is presented, in
// order, exactly one latency after capture; the fault is logged and visible in the
// trace; the overlay comes back after it; the frames lost are exactly those injected.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "../app/fakes.hpp"
#include "../sim/test_util.hpp"
#include "endotower/app/no_signal_source.hpp"
#include "endotower/app/pipeline.hpp"
#include "endotower/app/status_badge.hpp"
#include "endotower/app/trace_reader.hpp"
#include "endotower/sim/fault_source.hpp"
#include "endotower/sim/recorded_source.hpp"
#include "endotower/sim/virtual_clock.hpp"

namespace endotower::test {
namespace {

using Kind = sim::CaptureFault::Kind;
constexpr int kFrames = 180;  // 3 s at 60 fps
constexpr int kW = 64, kH = 48;

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

class CollectLog final : public app::Log {
public:
    void write(app::LogLevel, std::string_view m) override { lines.emplace_back(m); }
    bool has(std::string_view s) const {
        for (const auto& l : lines)
            if (l.find(s) != std::string::npos) return true;
        return false;
    }
    std::vector<std::string> lines;
};

// The recording: kFrames PNGs, frame i's first pixel blue = i & 0xff, a lit disc
// around the middle (the badge measures light inside the field of view).
const std::string& recording() {
    static sim::test::TempDir dir("faults");
    static const bool written = [] {
        for (int i = 0; i < kFrames; ++i) {
            cv::Mat m(kH, kW, CV_8UC3, cv::Scalar(0, 0, 0));
            for (int y = 8; y < 40; ++y)
                for (int x = 16; x < 48; ++x)
                    m.at<cv::Vec3b>(y, x) = {90, 120, static_cast<std::uint8_t>(150 + i % 50)};
            m.at<cv::Vec3b>(0, 0) = {static_cast<std::uint8_t>(i & 0xff), 0, 0};
            char name[32];
            std::snprintf(name, sizeof name, "f%04d.png", i);
            cv::imwrite(dir.file(name), m);
        }
        return true;
    }();
    (void)written;
    static const std::string path = dir.path().string();
    return path;
}

struct Replay {
    explicit Replay(std::vector<sim::CaptureFault> faults)
        : recorded({recording(), 60.0, 6}, clock),
          faulty(recorded, clock, std::move(faults)),
          no_signal(faulty, clock, log),
          sink(clock) {}

    app::PipelineSummary run(hal::ControlInput* input = nullptr) {
        if (!recorded.open()) ADD_FAILURE() << recorded.error();
        app::Pipeline p({}, no_signal, sink, clock, input, &badge, &trace, log);
        return p.run();
    }

    sim::VirtualClock clock{1'000'000'000};
    sim::RecordedFrameSource recorded;
    sim::FaultInjectingSource faulty;
    CollectLog log;
    app::NoSignalSource no_signal;
    RecordingSink sink;
    app::StatusBadge badge;
    CollectTrace trace;
};

// The invariants of every case: every frame out, in order, at the fixed latency, and
// the real frames are the recording's minus exactly the dropped ones.
void expect_video_never_stopped(const Replay& r, const app::PipelineSummary& s,
                                std::int64_t dropped) {
    ASSERT_TRUE(s.ok) << s.error;
    EXPECT_EQ(s.frames_out, s.frames_in);
    EXPECT_EQ(s.late_frames, 0);
    ASSERT_EQ(r.sink.shown.size(), static_cast<std::size_t>(s.frames_out));
    ASSERT_EQ(r.trace.records.size(), r.sink.shown.size());
    const hal::Nanos latency = s.latency_target_ns;
    EXPECT_EQ(latency, r.recorded.frame_period());
    for (std::size_t i = 0; i < r.sink.shown.size(); ++i) {
        const Shown& f = r.sink.shown[i];
        EXPECT_EQ(f.presented_ns - f.capture_ns, latency) << "frame " << i;
        if (i > 0) {
            EXPECT_GT(f.capture_ns, r.sink.shown[i - 1].capture_ns)
                << "frame " << i << " out of order";
        }
        EXPECT_EQ(r.trace.records[i].latency_ns, latency) << "frame " << i;
        EXPECT_FALSE(r.trace.records[i].late) << "frame " << i;
    }
    EXPECT_EQ(r.faulty.dropped_frames(), dropped);
    EXPECT_EQ(r.recorded.frames_read(), kFrames);
}

// After the fault, the overlay is back: the last frames show an analysis result.
void expect_recovered(const Replay& r) {
    ASSERT_GE(r.trace.records.size(), 10u);
    for (std::size_t i = r.trace.records.size() - 10; i < r.trace.records.size(); ++i) {
        EXPECT_FALSE(r.trace.records[i].passthrough) << "frame " << i;
        EXPECT_TRUE(r.sink.shown[i].had_overlay) << "frame " << i;
    }
}

// The recording's frames among those shown: frame k of the recording is captured at
// t0 + k * period and carries k in its first byte (the no-signal card is black).
std::vector<std::int64_t> recording_indices_shown(const Replay& r) {
    std::vector<std::int64_t> out;
    const double period = 1e9 / r.recorded.frame_rate();
    for (const Shown& f : r.sink.shown) {
        const double k = static_cast<double>(f.capture_ns - 1'000'000'000) / period;
        if (std::abs(k - std::llround(k)) < 1e-3 && f.first_byte == (std::llround(k) & 0xff))
            out.push_back(std::llround(k));
    }
    return out;
}

TEST(CaptureFaults, StallShorterThanTheNoSignalDelayLosesOnlyTheStalledFrames) {
    // 13 frames = 217 ms: one 200 ms source timeout, no no-signal card (250 ms).
    Replay r({{Kind::kStall, 60, 13}});
    const auto s = r.run();
    expect_video_never_stopped(r, s, 13);
    EXPECT_EQ(s.frames_in, kFrames - 13);
    EXPECT_EQ(s.source_gaps, 13);  // the trace's seq jumps by 14 once
    int jumps = 0;
    for (std::size_t i = 1; i < r.trace.records.size(); ++i)
        jumps += r.trace.records[i].seq - r.trace.records[i - 1].seq == 14;
    EXPECT_EQ(jumps, 1);
    EXPECT_TRUE(r.log.has("no frame from the source")) << "stall not logged";
    EXPECT_FALSE(r.no_signal.showing_card());
    expect_recovered(r);
}

TEST(CaptureFaults, SignalLossShowsTheNoSignalCardThenTheVideoAgain) {
    Replay r({{Kind::kStall, 30, 60}});  // 1 s without signal
    const auto s = r.run();
    expect_video_never_stopped(r, s, 60);
    // Cards: one per 200 ms source timeout once 250 ms have passed without a frame.
    const std::int64_t real = kFrames - 60;
    EXPECT_EQ(s.frames_in - real, 3) << "card frames at 400, 600 and 800 ms of the outage";
    EXPECT_TRUE(r.log.has("no frame from the source"));
    EXPECT_TRUE(r.log.has("capture signal is back")) << "recovery not logged";
    EXPECT_FALSE(r.no_signal.showing_card());
    // The real frames shown are the recording minus [30, 90), in order.
    const auto idx = recording_indices_shown(r);
    ASSERT_EQ(idx.size(), static_cast<std::size_t>(real));
    for (std::size_t i = 0; i < idx.size(); ++i)
        EXPECT_EQ(idx[i],
                  i < 30 ? static_cast<std::int64_t>(i) : static_cast<std::int64_t>(i) + 60);
    expect_recovered(r);
}

TEST(CaptureFaults, DisappearAndReappearRestartsTheSequenceWithoutStoppingTheVideo) {
    Replay r({{Kind::kDisappear, 50, 40}});
    const auto s = r.run();
    expect_video_never_stopped(r, s, 40);
    EXPECT_TRUE(r.log.has("capture signal is back"));
    // The reopened device counts from 0: the trace shows the reset.
    bool reset = false;
    for (std::size_t i = 1; i < r.trace.records.size(); ++i)
        reset = reset || r.trace.records[i].seq < r.trace.records[i - 1].seq;
    EXPECT_TRUE(reset);
    expect_recovered(r);
}

TEST(CaptureFaults, CorruptAndTruncatedFramesAreShownAndAnalysedWithoutHarm) {
    Replay r({{Kind::kCorrupt, 40, 5}, {Kind::kTruncate, 100, 5}});
    const auto s = r.run();
    expect_video_never_stopped(r, s, 0);
    EXPECT_EQ(s.frames_in, kFrames);
    EXPECT_EQ(s.faults, 0);  // the analysis neither threw nor hung on them
    // Frame-exact: the corrupt ones carry the noise, the truncated keep their top row.
    for (int i = 100; i < 105; ++i)
        EXPECT_EQ(r.sink.shown[static_cast<std::size_t>(i)].first_byte, i & 0xff);
    for (int i : {0, 39, 45, 99, 105, 179})
        EXPECT_EQ(r.sink.shown[static_cast<std::size_t>(i)].first_byte, i & 0xff);
    expect_recovered(r);
}

TEST(CaptureFaults, ResolutionAndPixelFormatChangeMidStreamAndBack) {
    Replay r({{Kind::kResize, 40, 30, 32, 24},
              {Kind::kPixelFormat, 90, 20, 0, 0, hal::PixelFormat::kYuyv},
              {Kind::kPixelFormat, 120, 20, 0, 0, hal::PixelFormat::kGray8}});
    const auto s = r.run();
    expect_video_never_stopped(r, s, 0);
    EXPECT_EQ(s.frames_in, kFrames);
    EXPECT_EQ(s.format_changes, 6);  // each change and each return
    std::vector<std::pair<int, std::string>> changes;
    for (const auto& rec : r.trace.records)
        if (rec.format_change)
            changes.emplace_back(static_cast<int>(rec.frame), rec.format_change->pixel_format);
    ASSERT_EQ(changes.size(), 6u);
    const int at[] = {40, 70, 90, 110, 120, 140};
    const char* pf[] = {"bgr24", "bgr24", "yuyv", "bgr24", "gray8", "bgr24"};
    for (std::size_t i = 0; i < 6; ++i) {
        EXPECT_EQ(changes[i].first, at[i]);
        EXPECT_EQ(changes[i].second, pf[i]);
    }
    EXPECT_EQ(r.sink.shown[40].width, 32);
    EXPECT_EQ(r.sink.shown[70].width, kW);
    EXPECT_TRUE(r.log.has("input format changed to 32x24"));
    expect_recovered(r);
}

// A handle that sends 1000 events with every frame.
class FloodInput final : public hal::ControlInput {
public:
    explicit FloodInput(hal::Clock& clock) : clock_(clock) {}
    bool poll(hal::ControlEvent& out) override {
        const hal::Nanos now = clock_.now();
        if (now != last_) last_ = now, left_ = 1000;
        if (left_ == 0) return false;
        --left_;
        out = {hal::ControlEvent::Kind::kWheel, 0, 1, now};
        ++sent;
        return true;
    }
    std::int64_t sent = 0;

private:
    hal::Clock& clock_;
    hal::Nanos last_ = -1;
    int left_ = 0;
};

TEST(CaptureFaults, HandleEventFloodIsBoundedInTheTraceAndNeverDelaysTheVideo) {
    Replay r({});
    FloodInput flood(r.clock);
    const auto s = r.run(&flood);
    expect_video_never_stopped(r, s, 0);
    EXPECT_EQ(s.frames_in, kFrames);
    EXPECT_GE(flood.sent, 1000 * kFrames);
    for (const auto& rec : r.trace.records) {
        EXPECT_LE(rec.input.size(), 8u) << "frame " << rec.frame;
        if (rec.input.size() == 8u) {
            EXPECT_NE(rec.extra.find("\"input_dropped\":"), std::string::npos)
                << "frame " << rec.frame;
        }
    }
    expect_recovered(r);
}

}  // namespace
}  // namespace endotower::test
