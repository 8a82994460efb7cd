#include "analysis_worker.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <exception>
#include <new>

namespace endotower::app {

const char* to_string(AnalysisFault f) {
    switch (f) {
        case AnalysisFault::kNone: return "none";
        case AnalysisFault::kThrew: return "analysis_threw";
        case AnalysisFault::kOutOfMemory: return "analysis_out_of_memory";
        case AnalysisFault::kHung: return "analysis_hung";
    }
    return "unknown";
}

AnalysisWorker::AnalysisWorker(AnalysisStage& stage, hal::Clock& clock, Log& log)
    : stage_(stage), clock_(clock), log_(log) {
    for (auto& s : slots_) s = std::make_unique<AnalysisResult>();
    thread_ = std::thread([this] { loop(); });
}

AnalysisWorker::~AnalysisWorker() {
    {
        std::lock_guard lk(mu_);
        quit_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
}

bool AnalysisWorker::shutdown(hal::Nanos wall_ns) {
    {
        std::lock_guard lk(mu_);
        quit_ = true;
    }
    cv_.notify_all();
    if (!wait_idle(wall_ns)) {
        thread_.detach();
        return false;
    }
    return true;
}

bool AnalysisWorker::configure(const hal::FrameFormat& format) {
    format_ = format;
    input_.assign(format.size_bytes(), 0);
    job_frame_ = hal::Frame{};
    job_frame_.format = format;
    job_frame_.data = input_.data();
    {
        std::lock_guard lk(mu_);
        for (std::size_t i = 0; i < kSlots; ++i) {
            slots_[i]->canvas.configure(format.width, format.height);
            slots_[i]->frame_index = -1;
            state_[i] = SlotState::kFree;
        }
        last_fault_ = AnalysisFault::kNone;
    }
    try {
        stage_.configure(format);
    } catch (const std::exception& e) {
        log_.printf(LogLevel::kError, "analysis stage %.*s failed to configure: %s",
                    static_cast<int>(stage_.name().size()), stage_.name().data(), e.what());
        return false;
    }
    return true;
}

bool AnalysisWorker::idle() const {
    std::lock_guard lk(mu_);
    return !busy_;
}

bool AnalysisWorker::wait_idle(hal::Nanos wall_ns) const {
    std::unique_lock lk(mu_);
    return cv_.wait_for(lk, std::chrono::nanoseconds(wall_ns), [this] { return !busy_; });
}

void AnalysisWorker::submit(const hal::Frame& frame, std::int64_t index, hal::Nanos submit_ns,
                            std::span<const hal::ControlEvent> events,
                            hal::Nanos virtual_cost_ns) {
    // The copy keeps capture buffers out of the stage's hands: a hung stage can
    // never hold one, and the source may recycle them freely.
    const std::size_t rows = static_cast<std::size_t>(frame.format.height);
    if (frame.format.stride == format_.stride) {
        std::memcpy(input_.data(), frame.data, format_.size_bytes());
    } else {
        const std::size_t row_bytes =
            static_cast<std::size_t>(format_.width) * hal::bytes_per_pixel(format_.pixel_format);
        for (std::size_t y = 0; y < rows; ++y)
            std::memcpy(input_.data() + y * format_.stride, frame.data + y * frame.format.stride,
                        row_bytes);
    }
    job_frame_.capture_ns = frame.capture_ns;
    job_frame_.sequence = frame.sequence;
    job_event_count_ = std::min(events.size(), kMaxEvents);
    std::copy_n(events.begin(), job_event_count_, job_events_.begin());
    {
        std::lock_guard lk(mu_);
        job_index_ = index;
        job_submit_ns_ = submit_ns;
        job_cost_ns_ = virtual_cost_ns;
        job_started_ns_ = clock_.now();
        busy_ = true;
    }
    cv_.notify_all();
}

hal::Nanos AnalysisWorker::job_started_ns() const {
    std::lock_guard lk(mu_);
    return job_started_ns_;
}

AnalysisFault AnalysisWorker::last_fault(hal::Nanos* known_at_ns) const {
    std::lock_guard lk(mu_);
    if (known_at_ns != nullptr) *known_at_ns = last_fault_known_ns_;
    return last_fault_;
}

hal::Nanos AnalysisWorker::virtual_busy_until() const {
    std::lock_guard lk(mu_);
    return virtual_busy_until_;
}

int AnalysisWorker::take_free_slot() {
    for (std::size_t i = 0; i < kSlots; ++i) {
        if (state_[i] == SlotState::kFree) {
            state_[i] = SlotState::kWriting;
            return static_cast<int>(i);
        }
    }
    return -1;
}

void AnalysisWorker::loop() {
    std::unique_lock lk(mu_);
    for (;;) {
        cv_.wait(lk, [this] { return busy_ || quit_; });
        if (!busy_) return;  // quit while idle
        lk.unlock();
        run_job();
        lk.lock();
        busy_ = false;
        cv_.notify_all();
        if (quit_) return;
    }
}

void AnalysisWorker::run_job() {
    int slot;
    {
        std::lock_guard lk(mu_);
        slot = take_free_slot();
    }
    // Four slots, at most one writing, one in use and two ready: one is always free.
    if (slot < 0) return;
    AnalysisResult& r = *slots_[static_cast<std::size_t>(slot)];
    r.canvas.clear();
    r.trace.clear();
    r.trace.begin_object();
    AnalysisContext ctx{job_frame_, std::span<const hal::ControlEvent>(job_events_.data(), job_event_count_),
                        r.canvas, r.trace, job_cost_ns_};
    AnalysisFault fault = AnalysisFault::kNone;
    const hal::Nanos t0 = clock_.now();
    const auto w0 = std::chrono::steady_clock::now();
    try {
        stage_.process(ctx);
    } catch (const std::bad_alloc&) {
        fault = AnalysisFault::kOutOfMemory;
    } catch (const std::exception& e) {
        fault = AnalysisFault::kThrew;
        log_.printf(LogLevel::kWarning, "analysis stage threw on frame %lld: %s",
                    static_cast<long long>(job_index_), e.what());
    } catch (...) {
        fault = AnalysisFault::kThrew;
    }
    r.trace.end_object();
    r.duration_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                        std::chrono::steady_clock::now() - w0)
                        .count();
    // Deterministic replay: ready after the virtual cost; live: when it really is.
    const hal::Nanos ready = clock_.is_virtual() ? job_submit_ns_ + ctx.virtual_cost_ns
                                                 : std::max(clock_.now(), t0);
    std::lock_guard lk(mu_);
    virtual_busy_until_ = ready;
    last_fault_ = fault;
    last_fault_known_ns_ = ready;
    if (fault != AnalysisFault::kNone) {
        r.canvas.clear();
        state_[static_cast<std::size_t>(slot)] = SlotState::kFree;
        return;
    }
    r.frame_index = job_index_;
    r.ready_ns = ready;
    state_[static_cast<std::size_t>(slot)] = SlotState::kReady;
    // Keep only the newest kMaxReady ready results.
    std::size_t ready_count = 0;
    for (auto s : state_) ready_count += (s == SlotState::kReady);
    while (ready_count > kMaxReady) {
        int oldest = -1;
        for (std::size_t i = 0; i < kSlots; ++i)
            if (state_[i] == SlotState::kReady &&
                (oldest < 0 || slots_[i]->frame_index < slots_[static_cast<std::size_t>(oldest)]->frame_index))
                oldest = static_cast<int>(i);
        state_[static_cast<std::size_t>(oldest)] = SlotState::kFree;
        --ready_count;
    }
}

const AnalysisResult* AnalysisWorker::acquire(std::int64_t max_index, hal::Nanos t) {
    std::lock_guard lk(mu_);
    int best = -1;
    for (std::size_t i = 0; i < kSlots; ++i) {
        const AnalysisResult& r = *slots_[i];
        if (state_[i] != SlotState::kReady || r.frame_index > max_index || r.ready_ns > t) continue;
        if (best < 0 || r.frame_index > slots_[static_cast<std::size_t>(best)]->frame_index)
            best = static_cast<int>(i);
    }
    if (best < 0) return nullptr;
    state_[static_cast<std::size_t>(best)] = SlotState::kInUse;
    return slots_[static_cast<std::size_t>(best)].get();
}

void AnalysisWorker::release(const AnalysisResult* r) {
    if (r == nullptr) return;
    std::lock_guard lk(mu_);
    for (std::size_t i = 0; i < kSlots; ++i) {
        if (slots_[i].get() != r) continue;
        // Back to ready unless two newer results have been published meanwhile.
        std::size_t newer = 0;
        for (std::size_t j = 0; j < kSlots; ++j)
            newer += (state_[j] == SlotState::kReady && slots_[j]->frame_index > r->frame_index);
        state_[i] = newer >= kMaxReady ? SlotState::kFree : SlotState::kReady;
    }
}

}  // namespace endotower::app
