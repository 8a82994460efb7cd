#include "endotower/app/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <vector>

#include "analysis_worker.hpp"
#include "endotower/app/latency_histogram.hpp"

namespace endotower::app {

namespace {

hal::Nanos wall_now() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

constexpr std::size_t kTraceEventsPerFrame = 8;

struct QueuedFrame {
    hal::Frame frame{};
    std::int64_t index = 0;
    hal::Nanos due_ns = 0;
    hal::Nanos capture_wait_ns = 0;
    std::array<hal::ControlEvent, kTraceEventsPerFrame> events{};
    std::size_t event_count = 0;
    std::size_t events_dropped = 0;
    bool format_changed = false;
};

struct OverlayChoice {
    const AnalysisResult* result = nullptr;
    std::int64_t age = -1;  // -1: no result
    bool passthrough = false;
    const char* fault = nullptr;
};

}  // namespace

struct Pipeline::Impl {
    Impl(PipelineConfig c, hal::FrameSource& src, hal::VideoSink& snk, hal::Clock& clk,
         hal::ControlInput* in, AnalysisStage* stg, TraceSink* tr, Log& lg)
        : cfg(c), source(src), sink(snk), clock(clk), input(in), stage(stg), trace(tr), log(lg),
          histogram(std::make_unique<LatencyHistogram>()) {}

    bool start();
    void on_frame(const hal::Frame& frame, hal::Nanos capture_wait_ns);
    void present_due(hal::Nanos horizon_ns);
    void present_front();
    OverlayChoice choose_overlay(const QueuedFrame& q, hal::Nanos now);
    void submit_analysis(const hal::Frame& frame, std::int64_t index);
    bool reconfigure();
    void write_trace(const QueuedFrame& q, hal::Nanos presented, const OverlayChoice& o,
                     hal::Nanos present_wall_ns);
    void set_hung(bool hung);
    void finish(PipelineSummary& s, hal::Nanos wall_start);

    PipelineConfig cfg;
    hal::FrameSource& source;
    hal::VideoSink& sink;
    hal::Clock& clock;
    hal::ControlInput* input;
    AnalysisStage* stage;
    TraceSink* trace;
    Log& log;

    std::unique_ptr<AnalysisWorker> worker;
    std::unique_ptr<LatencyHistogram> histogram;
    hal::Nanos period = 0;

    // Frames waiting for their present time: a fixed ring, at most the source's pool.
    std::vector<QueuedFrame> ring;
    std::size_t head = 0, count = 0;

    std::array<hal::ControlEvent, AnalysisWorker::kMaxEvents> pending_events{};
    std::size_t pending_count = 0;

    JsonLine line;
    PipelineSummary summary;
    std::int64_t next_index = 0;
    std::uint64_t last_sequence = 0;
    bool have_sequence = false;
    bool format_changed = false;
    bool reconfig_pending = false;
    bool analysis_disabled = false;
    bool hung = false;
    AnalysisFault reported_fault = AnalysisFault::kNone;
    hal::Nanos first_capture = -1, last_capture = 0;
};

Pipeline::Pipeline(PipelineConfig config, hal::FrameSource& source, hal::VideoSink& sink,
                   hal::Clock& clock, hal::ControlInput* input, AnalysisStage* stage,
                   TraceSink* trace, Log& log)
    : impl_(std::make_unique<Impl>(config, source, sink, clock, input, stage, trace, log)) {}

Pipeline::~Pipeline() {
    if (impl_ && impl_->worker && !impl_->worker->shutdown(impl_->cfg.analysis_wall_timeout_ns)) {
        // The stage is stuck inside process(): its thread still uses the worker, so
        // the worker is left alive on purpose. The process is about to end.
        impl_->log.write(LogLevel::kWarning, "analysis stage still hung at shutdown; abandoned");
        (void)impl_->worker.release();
    }
}

bool Pipeline::Impl::start() {
    if (!source.start()) {
        summary.ok = false;
        summary.error = source.error();
        return false;
    }
    period = source.frame_period();
    if (cfg.latency_ns <= 0) cfg.latency_ns = period;
    if (cfg.compose_budget_ns <= 0) cfg.compose_budget_ns = std::min<hal::Nanos>(4 * hal::kMillisecond, cfg.latency_ns / 2);
    cfg.compose_budget_ns = std::min(cfg.compose_budget_ns, cfg.latency_ns);
    if (cfg.analysis_timeout_ns <= 0) cfg.analysis_timeout_ns = 4 * period;
    if (cfg.analysis_wall_timeout_ns <= 0) cfg.analysis_wall_timeout_ns = 2 * hal::kSecond;
    if (cfg.analysis_virtual_cost_ns <= 0) cfg.analysis_virtual_cost_ns = period / 2;
    if (cfg.max_overlay_age <= 0) cfg.max_overlay_age = 3;
    if (cfg.late_tolerance_ns <= 0) cfg.late_tolerance_ns = hal::kMillisecond;
    summary.latency_target_ns = cfg.latency_ns;

    // Frames in flight: those within the latency window, bounded by the pool less
    // one buffer that always stays with the source, so capture never starves.
    ring.assign(static_cast<std::size_t>(std::max(1, source.buffer_count() - 1)), QueuedFrame{});
    const hal::Nanos window = (cfg.latency_ns + period - 1) / std::max<hal::Nanos>(period, 1) + 1;
    if (static_cast<hal::Nanos>(ring.size()) < window)
        log.printf(LogLevel::kWarning,
                   "latency of %.1f ms needs %lld capture buffers, the source has %d: "
                   "frames will be dropped at capture",
                   static_cast<double>(cfg.latency_ns) / 1e6, static_cast<long long>(window) + 1,
                   source.buffer_count());
    if (!sink.configure(source.format())) {
        summary.ok = false;
        summary.error = sink.error();
        return false;
    }
    if (stage != nullptr) {
        worker = std::make_unique<AnalysisWorker>(*stage, clock, log);
        analysis_disabled = !worker->configure(source.format());
    }
    return true;
}

bool Pipeline::Impl::reconfigure() {
    present_due(INT64_MAX);  // the queued frames still have the old format
    const hal::FrameFormat f = source.format();
    log.printf(LogLevel::kInfo, "input format changed to %dx%d %.*s", f.width, f.height,
               static_cast<int>(hal::to_string(f.pixel_format).size()),
               hal::to_string(f.pixel_format).data());
    ++summary.format_changes;
    format_changed = true;
    if (!sink.configure(f)) {
        summary.ok = false;
        summary.error = sink.error();
        return false;
    }
    reconfig_pending = worker != nullptr;
    return true;
}

void Pipeline::Impl::set_hung(bool now_hung) {
    if (now_hung == hung) return;
    hung = now_hung;
    if (hung) {
        ++summary.faults;
        log.write(LogLevel::kError, "analysis stage hung past its deadline; showing raw video");
    } else {
        log.write(LogLevel::kInfo, "analysis stage returned; overlays resume");
    }
}

void Pipeline::Impl::submit_analysis(const hal::Frame& frame, std::int64_t index) {
    if (!worker || analysis_disabled) return;
    if (reconfig_pending) {
        if (!worker->idle()) return;
        analysis_disabled = !worker->configure(frame.format);
        reconfig_pending = false;
        if (analysis_disabled) return;
    }
    if (clock.is_virtual()) {
        // Deterministic replay: busy in virtual time until the last job's cost is
        // spent; then the real thread must be done too (bounded wait).
        if (frame.capture_ns < worker->virtual_busy_until()) return;
        if (!worker->idle()) {
            if (hung || !worker->wait_idle(cfg.analysis_wall_timeout_ns)) {
                set_hung(true);
                return;
            }
        }
    } else if (!worker->idle()) {
        return;  // busy: this frame is not analysed
    }
    set_hung(false);
    worker->submit(frame, index, frame.capture_ns,
                   std::span<const hal::ControlEvent>(pending_events.data(), pending_count),
                   cfg.analysis_virtual_cost_ns);
    pending_count = 0;
    ++summary.analysed_frames;
}

void Pipeline::Impl::on_frame(const hal::Frame& frame, hal::Nanos capture_wait_ns) {
    if (have_sequence && frame.sequence > last_sequence + 1)
        summary.source_gaps += static_cast<std::int64_t>(frame.sequence - last_sequence - 1);
    last_sequence = frame.sequence;
    have_sequence = true;
    if (first_capture < 0) first_capture = frame.capture_ns;
    last_capture = frame.capture_ns;

    // Ring full (the pool is smaller than the latency window): show the oldest at
    // its due time first. The latency holds; a live source drops frames instead.
    if (count == ring.size()) present_front();

    QueuedFrame& q = ring[(head + count) % ring.size()];
    ++count;
    q.frame = frame;
    q.index = next_index++;
    q.due_ns = frame.capture_ns + cfg.latency_ns;
    q.capture_wait_ns = capture_wait_ns;
    q.event_count = 0;
    q.events_dropped = 0;
    q.format_changed = format_changed;
    format_changed = false;
    ++summary.frames_in;

    hal::ControlEvent ev;
    while (input != nullptr && input->poll(ev)) {
        if (q.event_count < q.events.size()) q.events[q.event_count++] = ev;
        else ++q.events_dropped;
        if (pending_count == pending_events.size()) {
            // The analysis is far behind: drop the oldest so the newest still arrive.
            std::move(pending_events.begin() + 1, pending_events.end(), pending_events.begin());
            --pending_count;
        }
        pending_events[pending_count++] = ev;
    }
    submit_analysis(frame, q.index);
}

OverlayChoice Pipeline::Impl::choose_overlay(const QueuedFrame& q, hal::Nanos now) {
    OverlayChoice o;
    if (!worker) return o;
    if (analysis_disabled) {
        o.passthrough = true;
        o.fault = "analysis_disabled";
        return o;
    }
    if (reconfig_pending || worker->format() != q.frame.format) return o;
    if (clock.is_virtual()) {
        if (!worker->idle() && (hung || !worker->wait_idle(cfg.analysis_wall_timeout_ns)))
            set_hung(true);
    } else if (!worker->idle() && now - worker->job_started_ns() > cfg.analysis_timeout_ns) {
        set_hung(true);
    }
    if (hung && worker->idle()) set_hung(false);
    if (hung) {
        o.passthrough = true;
        o.fault = to_string(AnalysisFault::kHung);
        return o;
    }
    hal::Nanos known_at = 0;
    const AnalysisFault fault = worker->last_fault(&known_at);
    if (fault != AnalysisFault::kNone && known_at <= now) {
        if (fault != reported_fault) ++summary.faults;
        reported_fault = fault;
        o.passthrough = true;
        o.fault = to_string(fault);
        return o;
    }
    if (fault == AnalysisFault::kNone) reported_fault = AnalysisFault::kNone;
    o.result = worker->acquire(q.index, now);
    if (o.result == nullptr) return o;
    o.age = q.index - o.result->frame_index;
    if (o.age > cfg.max_overlay_age) {
        // Too old to match the picture: a stale cursor is worse than none.
        worker->release(o.result);
        o.result = nullptr;
        o.passthrough = true;
        o.fault = "analysis_stale";
    }
    return o;
}

void Pipeline::Impl::present_front() {
    QueuedFrame& q = ring[head];
    const hal::Nanos compose_at = q.due_ns - cfg.compose_budget_ns;
    if (clock.now() < compose_at) clock.sleep_until(compose_at);
    const OverlayChoice o = choose_overlay(q, clock.now());
    const hal::Nanos w0 = wall_now();
    const hal::Nanos presented =
        sink.present(q.frame, o.result != nullptr ? &o.result->canvas.layer() : nullptr, q.due_ns);
    const hal::Nanos present_wall = wall_now() - w0;
    if (presented < 0 && summary.ok) {
        // The picture must keep flowing: log once, keep presenting.
        log.printf(LogLevel::kError, "video sink: %s", sink.error().c_str());
        summary.ok = false;
        summary.error = sink.error();
    }
    write_trace(q, presented, o, present_wall);
    if (worker) worker->release(o.result);
    source.release(q.frame);
    head = (head + 1) % ring.size();
    --count;
}

void Pipeline::Impl::present_due(hal::Nanos horizon_ns) {
    while (count > 0 && ring[head].due_ns <= horizon_ns) present_front();
}

void Pipeline::Impl::write_trace(const QueuedFrame& q, hal::Nanos presented,
                                 const OverlayChoice& o, hal::Nanos present_wall_ns) {
    const hal::Nanos latency = presented - q.frame.capture_ns;
    const bool late = presented > q.due_ns + cfg.late_tolerance_ns;
    ++summary.frames_out;
    summary.late_frames += late;
    summary.passthrough_frames += o.passthrough;
    histogram->add(latency);
    if (trace == nullptr) return;

    line.clear();
    line.begin_object()
        .field("frame", q.index)
        .field("seq", static_cast<std::int64_t>(q.frame.sequence))
        .field("capture_ns", q.frame.capture_ns)
        .field("present_ns", presented)
        .field("latency_ns", latency)
        .field("late", late);
    line.begin_object("stages_us")
        .field("capture_wait", q.capture_wait_ns / 1000)
        .field("present", present_wall_ns / 1000);
    if (o.result != nullptr) line.field("analysis", o.result->duration_ns / 1000);
    line.end_object();
    if (o.age >= 0) line.field("analysis_age", o.age);
    else line.null_field("analysis_age");
    line.field("passthrough", o.passthrough);
    if (o.fault != nullptr) line.field("fault", o.fault);
    else line.null_field("fault");
    line.begin_array("input");
    for (std::size_t i = 0; i < q.event_count; ++i) {
        const hal::ControlEvent& e = q.events[i];
        line.begin_object().field("kind", hal::to_string(e.kind)).field("t_ns", e.time_ns);
        if (e.kind == hal::ControlEvent::Kind::kWheel) line.field("delta", static_cast<int>(e.delta));
        else line.field("button", static_cast<int>(e.button));
        line.end_object();
    }
    line.end_array();
    if (q.events_dropped > 0) line.field("input_dropped", static_cast<std::int64_t>(q.events_dropped));
    if (q.format_changed) {
        line.begin_object("format_change")
            .field("width", q.frame.format.width)
            .field("height", q.frame.format.height)
            .field("pixel_format", hal::to_string(q.frame.format.pixel_format))
            .end_object();
    }
    if (o.result != nullptr) {
        // The stage's members, written as "{...}": splice without the braces.
        std::string_view members = o.result->trace.view();
        if (members.size() >= 2 && !o.result->trace.overflowed())
            line.raw_members(members.substr(1, members.size() - 2));
    }
    line.end_object();
    trace->write(line.view());
}

void Pipeline::Impl::finish(PipelineSummary& s, hal::Nanos wall_start) {
    present_due(INT64_MAX);
    if (!sink.finish() && s.ok) {
        s.ok = false;
        s.error = sink.error();
    }
    source.stop();
    s.latency_min_ns = histogram->min();
    s.latency_max_ns = histogram->max();
    s.latency_median_ns = histogram->quantile(0.5);
    s.latency_p99_ns = histogram->quantile(0.99);
    if (first_capture >= 0) s.media_duration_ns = last_capture - first_capture + period;
    s.wall_seconds = static_cast<double>(wall_now() - wall_start) / 1e9;
}

PipelineSummary Pipeline::run() {
    Impl& m = *impl_;
    const hal::Nanos wall_start = wall_now();
    if (!m.start()) return m.summary;
    const hal::Nanos timeout = std::max<hal::Nanos>(4 * m.period, 200 * hal::kMillisecond);
    int idle_polls = 0;
    bool warned_stall = false;
    while (!stop_.load(std::memory_order_relaxed)) {
        hal::Frame frame;
        const hal::Nanos w0 = wall_now();
        const hal::SourceStatus st = m.source.next(frame, timeout);
        const hal::Nanos waited = wall_now() - w0;
        if (st == hal::SourceStatus::kEndOfStream) break;
        if (st == hal::SourceStatus::kError) {
            m.summary.ok = false;
            m.summary.error = m.source.error();
            break;
        }
        if (st == hal::SourceStatus::kFormatChange) {
            if (!m.reconfigure()) break;
            continue;
        }
        if (st == hal::SourceStatus::kTimeout) {
            // Frames still queued go out on time even while the input is stalled.
            m.present_due(m.clock.now());
            if (!warned_stall) m.log.write(LogLevel::kWarning, "no frame from the source; waiting");
            warned_stall = true;
            // A recording under a virtual clock never stalls: stop rather than spin.
            if (m.clock.is_virtual() && ++idle_polls > 100) {
                m.summary.ok = false;
                m.summary.error = "source stalled: " + m.source.error();
                break;
            }
            continue;
        }
        idle_polls = 0;
        warned_stall = false;
        m.on_frame(frame, waited);
        // Present what falls due before the next frame is expected.
        m.present_due(frame.capture_ns + m.period);
    }
    m.finish(m.summary, wall_start);
    return m.summary;
}

}  // namespace endotower::app
