// AnalysisWorker (internal to the pipeline): one thread, started once, that runs an
// AnalysisStage on a pipeline-owned copy of a frame and publishes results into a
// fixed pool of slots (overlay canvas + trace members).
#pragma once

#include <array>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/app/log.hpp"
#include "endotower/hal/clock.hpp"

namespace endotower::app {

enum class AnalysisFault { kNone, kThrew, kOutOfMemory, kHung };
const char* to_string(AnalysisFault f);

struct AnalysisResult {
    OverlayCanvas canvas;
    JsonLine trace;
    std::int64_t frame_index = -1;
    hal::Nanos ready_ns = 0;     // when it may be shown (virtual in deterministic replay)
    hal::Nanos duration_ns = 0;  // wall time the stage took
};

class AnalysisWorker {
public:
    static constexpr std::size_t kMaxEvents = 256;

    AnalysisWorker(AnalysisStage& stage, hal::Clock& clock, Log& log);
    // Joins the thread; call shutdown() first. A worker whose stage is hung must not
    // be destroyed (the owner leaks it on purpose: the process is ending).
    ~AnalysisWorker();

    // Asks the thread to finish and waits up to wall_ns; false if the stage is hung.
    bool shutdown(hal::Nanos wall_ns);

    // Allocates the input copy and result slots and configures the stage. Only when
    // idle(). False if the stage threw while configuring.
    bool configure(const hal::FrameFormat& format);
    const hal::FrameFormat& format() const { return format_; }

    bool idle() const;
    // Waits (wall clock) until idle or `wall_ns` passes; returns idle().
    bool wait_idle(hal::Nanos wall_ns) const;
    // Copies the frame and events and starts the job. Precondition: idle().
    void submit(const hal::Frame& frame, std::int64_t index, hal::Nanos submit_ns,
                std::span<const hal::ControlEvent> events, hal::Nanos virtual_cost_ns);

    // Clock time the running job started (RT hang detection); submit time of the last.
    hal::Nanos job_started_ns() const;
    // The last finished job: its fault (kNone if it succeeded), and when that became known.
    AnalysisFault last_fault(hal::Nanos* known_at_ns) const;
    // Virtual time until which the worker counts as busy (deterministic replay).
    hal::Nanos virtual_busy_until() const;

    // Newest published result with frame_index <= max_index and ready_ns <= t, held
    // until release(); nullptr if none.
    const AnalysisResult* acquire(std::int64_t max_index, hal::Nanos t);
    void release(const AnalysisResult* r);

private:
    enum class SlotState : std::uint8_t { kFree, kWriting, kReady, kInUse };
    static constexpr std::size_t kSlots = 4;
    static constexpr std::size_t kMaxReady = 2;

    void loop();
    void run_job();
    int take_free_slot();  // under mu_

    AnalysisStage& stage_;
    hal::Clock& clock_;
    Log& log_;
    hal::FrameFormat format_{};
    std::vector<std::uint8_t> input_;
    hal::Frame job_frame_{};
    std::int64_t job_index_ = -1;
    hal::Nanos job_submit_ns_ = 0, job_cost_ns_ = 0, job_started_ns_ = 0;
    std::array<hal::ControlEvent, kMaxEvents> job_events_{};
    std::size_t job_event_count_ = 0;

    std::array<std::unique_ptr<AnalysisResult>, kSlots> slots_{};
    std::array<SlotState, kSlots> state_{};

    mutable std::mutex mu_;
    mutable std::condition_variable cv_;
    bool busy_ = false, quit_ = false;
    AnalysisFault last_fault_ = AnalysisFault::kNone;
    hal::Nanos last_fault_known_ns_ = 0, virtual_busy_until_ = 0;
    std::thread thread_;
};

}  // namespace endotower::app
