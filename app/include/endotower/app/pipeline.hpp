// Pipeline: the fixed-latency video path and the analysis path beside it.
//
// Video path (the thread that calls run()): capture -> present at
//   present = capture + latency
// for every frame, in order, none repeated. The overlay is chosen at
// present - compose_budget from the newest analysis result ready by then.
// Analysis path (one worker thread, started once): the newest frame, copied into a
// pipeline-owned buffer when the worker is idle; frames arriving while it is busy
// are not analysed. A stage that throws, runs out of memory or runs past
// analysis_timeout turns the overlay off (raw passthrough) until it recovers.
//
// Deterministic replay (a virtual clock): the analysis costs virtual_cost per call
// in virtual time and the video path waits, bounded by analysis_wall_timeout, for the
// results it is owed, so the output is identical run after run.
//
// Parameters (0 = default): latency (one frame period), compose_budget (4 ms),
// analysis_timeout (4 frame periods), analysis_wall_timeout (2 s),
// analysis_virtual_cost (half a frame period), max_overlay_age (3 frames),
// late_tolerance (1 ms: the wake-up jitter allowed before a frame counts as late;
// the trace always records the exact latency).
// Borrows everything it is given; all must outlive run().
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/app/log.hpp"
#include "endotower/app/trace_writer.hpp"
#include "endotower/hal/clock.hpp"
#include "endotower/hal/control_input.hpp"
#include "endotower/hal/frame_source.hpp"
#include "endotower/hal/video_sink.hpp"

namespace endotower::app {

struct PipelineConfig {
    hal::Nanos latency_ns = 0;
    hal::Nanos compose_budget_ns = 0;
    hal::Nanos analysis_timeout_ns = 0;
    hal::Nanos analysis_wall_timeout_ns = 0;
    hal::Nanos analysis_virtual_cost_ns = 0;
    int max_overlay_age = 0;
    hal::Nanos late_tolerance_ns = 0;
};

struct PipelineSummary {
    std::int64_t frames_in = 0, frames_out = 0;
    std::int64_t late_frames = 0;         // presented after due + late_tolerance
    std::int64_t passthrough_frames = 0;  // overlay withheld by a fault
    std::int64_t analysed_frames = 0;
    std::int64_t source_gaps = 0;         // frames the source itself dropped (sequence)
    std::int64_t format_changes = 0;
    std::int64_t faults = 0;              // throw / oom / hang episodes
    hal::Nanos latency_target_ns = 0;
    hal::Nanos latency_min_ns = 0, latency_median_ns = 0, latency_p99_ns = 0, latency_max_ns = 0;
    hal::Nanos media_duration_ns = 0;     // last capture - first capture + one period
    double wall_seconds = 0.0;
    bool ok = true;                       // false: the source or sink failed
    std::string error;
};

class Pipeline {
public:
    // input, stage and trace may be null.
    Pipeline(PipelineConfig config, hal::FrameSource& source, hal::VideoSink& sink,
             hal::Clock& clock, hal::ControlInput* input, AnalysisStage* stage,
             TraceSink* trace, Log& log);
    ~Pipeline();
    Pipeline(const Pipeline&) = delete;
    Pipeline& operator=(const Pipeline&) = delete;

    // Runs until the source ends, fails, or request_stop(). The source must be
    // ready to start().
    PipelineSummary run();
    // Async-signal-safe.
    void request_stop() { stop_.store(true, std::memory_order_relaxed); }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::atomic<bool> stop_{false};
};

}  // namespace endotower::app
