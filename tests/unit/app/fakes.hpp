// Test doubles for the pipeline: an in-memory frame source paced by a clock, a sink
// that records what it was shown, and scriptable analysis stages.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstring>
#include <functional>
#include <mutex>
#include <set>
#include <stdexcept>
#include <vector>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/hal/clock.hpp"
#include "endotower/hal/frame_source.hpp"
#include "endotower/hal/video_sink.hpp"

namespace endotower::test {

// A clock that only moves when told (the sim driver's VirtualClock does the same;
// the app's tests do not depend on drivers).
class ManualClock final : public hal::Clock {
public:
    hal::Nanos now() const override { return now_.load(); }
    void sleep_until(hal::Nanos t) override {
        hal::Nanos cur = now_.load();
        while (t > cur && !now_.compare_exchange_weak(cur, t)) {
        }
    }
    bool is_virtual() const override { return true; }

private:
    std::atomic<hal::Nanos> now_{1'000'000'000};
};

// Frames whose every byte is (index * 7 + offset) & 0xff, BGR24, paced at `period`.
class FakeSource final : public hal::FrameSource {
public:
    FakeSource(hal::Clock& clock, int frames, hal::Nanos period, int w = 64, int h = 48, int buffers = 6)
        : clock_(clock), frames_(frames), period_(period), buffers_(buffers) {
        set_format(w, h);
    }
    // From frame `at` on, frames have this size (kFormatChange is returned first).
    void change_size_at(int at, int w, int h) { change_at_ = at, change_w_ = w, change_h_ = h; }

    bool start() override {
        t0_ = clock_.now();
        allocate();
        return true;
    }
    void stop() override {}
    hal::SourceStatus next(hal::Frame& out, hal::Nanos) override {
        if (i_ == frames_) return hal::SourceStatus::kEndOfStream;
        if (i_ == change_at_ && format_.width != change_w_) {
            set_format(change_w_, change_h_);
            realloc_pending_ = true;
            return hal::SourceStatus::kFormatChange;
        }
        if (realloc_pending_) {
            // The contract: every old-format frame is back before the next call.
            if (outstanding() != 0) throw std::logic_error("next() after a format change with frames borrowed");
            allocate();
            realloc_pending_ = false;
        }
        int slot = -1;
        {
            std::lock_guard lk(mu_);
            for (int s = 0; s < buffers_; ++s)
                if (!borrowed_[s]) { slot = s; break; }
            if (slot < 0) return hal::SourceStatus::kTimeout;
            borrowed_[slot] = true;
        }
        const hal::Nanos t = t0_ + i_ * period_;
        if (clock_.now() < t) clock_.sleep_until(t);
        std::memset(pool_[slot].data(), fill_value(i_), pool_[slot].size());
        out.format = format_;
        out.data = pool_[slot].data();
        out.capture_ns = t;
        out.sequence = static_cast<std::uint64_t>(i_);
        out.buffer_index = slot;
        ++i_;
        return hal::SourceStatus::kFrame;
    }
    void release(const hal::Frame& f) override {
        std::lock_guard lk(mu_);
        if (!borrowed_.at(f.buffer_index)) throw std::logic_error("double release");
        borrowed_[f.buffer_index] = false;
    }
    hal::FrameFormat format() const override { return format_; }
    hal::Nanos frame_period() const override { return period_; }
    int buffer_count() const override { return buffers_; }
    const std::string& error() const override { return error_; }

    int outstanding() const {
        std::lock_guard lk(mu_);
        int n = 0;
        for (bool b : borrowed_) n += b;
        return n;
    }
    static std::uint8_t fill_value(int i) { return static_cast<std::uint8_t>(i * 7 + 3); }

private:
    void set_format(int w, int h) { format_ = {w, h, w * 3, hal::PixelFormat::kBgr24}; }
    void allocate() {
        pool_.assign(static_cast<std::size_t>(buffers_), std::vector<std::uint8_t>(format_.size_bytes()));
        borrowed_.assign(static_cast<std::size_t>(buffers_), false);
    }
    hal::Clock& clock_;
    int frames_;
    hal::Nanos period_;
    int buffers_;
    int i_ = 0, change_at_ = -1, change_w_ = 0, change_h_ = 0;
    bool realloc_pending_ = false;
    hal::Nanos t0_ = 0;
    hal::FrameFormat format_{};
    std::vector<std::vector<std::uint8_t>> pool_;
    std::vector<bool> borrowed_;
    mutable std::mutex mu_;
    std::string error_;
};

struct Shown {
    std::uint64_t sequence;
    hal::Nanos capture_ns, due_ns, presented_ns;
    std::uint8_t first_byte;
    bool had_overlay;
    int width;
};

// Records every present; "presents" at the due time (a display's next vblank).
class RecordingSink final : public hal::VideoSink {
public:
    explicit RecordingSink(hal::Clock& clock) : clock_(clock) {}
    bool configure(const hal::FrameFormat& f) override {
        formats.push_back(f);
        return true;
    }
    hal::Nanos present(const hal::Frame& v, const hal::OverlayLayer* o, hal::Nanos due) override {
        if (clock_.now() < due) clock_.sleep_until(due);
        if (on_present) on_present(v.sequence);
        shown.push_back({v.sequence, v.capture_ns, due, clock_.now(), v.data[0], o != nullptr && !o->empty(),
                         v.format.width});
        return clock_.now();
    }
    bool finish() override { return true; }
    const std::string& error() const override { return error_; }

    std::vector<Shown> shown;
    std::vector<hal::FrameFormat> formats;
    std::function<void(std::uint64_t sequence)> on_present;  // runs on the video thread

private:
    hal::Clock& clock_;
    std::string error_;
};

// Draws one opaque pixel and records which frames it saw. Behaviour per frame
// byte (the FakeSource fill value identifies the frame) is scriptable.
class ScriptedStage final : public app::AnalysisStage {
public:
    enum class Act { kOk, kThrow, kBadAlloc, kHang };
    std::function<Act(int frame)> script = [](int) { return Act::kOk; };
    hal::Nanos cost_ns = 0;  // 0: keep the pipeline's default

    std::string_view name() const override { return "scripted"; }
    void configure(const hal::FrameFormat& f) override { configured.push_back(f.width); }
    void process(app::AnalysisContext& ctx) override {
        const int frame = static_cast<int>(ctx.frame.sequence);
        {
            std::lock_guard lk(mu_);
            seen.push_back(frame);
            for (const auto& e : ctx.events) events.push_back(e);
        }
        if (cost_ns > 0) ctx.virtual_cost_ns = cost_ns;
        switch (script(frame)) {
            case Act::kThrow: throw std::runtime_error("scripted failure");
            case Act::kBadAlloc: throw std::bad_alloc();
            case Act::kHang: {
                std::unique_lock lk(mu_);
                hanging = true;
                cv_.wait(lk, [this] { return !hang_; });
                hanging = false;
                break;
            }
            case Act::kOk: break;
        }
        ctx.overlay.fill({0, 0, 1, 1}, app::Rgba{255, 0, 0, 255});
        ctx.trace.field("scripted_frame", frame);
        finished.fetch_add(1);
    }
    void release_hang() {
        {
            std::lock_guard lk(mu_);
            hang_ = false;
        }
        cv_.notify_all();
    }
    std::vector<int> seen_frames() {
        std::lock_guard lk(mu_);
        return seen;
    }

    std::vector<int> configured;
    std::vector<int> seen;
    std::vector<hal::ControlEvent> events;
    bool hanging = false;
    std::atomic<int> finished{0};

private:
    std::mutex mu_;
    std::condition_variable cv_;
    bool hang_ = true;
};

}  // namespace endotower::test
