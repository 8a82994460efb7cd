// FaultInjectingSource: a FrameSource decorator that injects capture faults into a
// replay (issue 10, docs/reliability.md), on a scenario of faults by frame index.
//
// Inputs: the inner source (borrowed, BGR24 frames, e.g. a RecordedFrameSource) and
// the clock it is paced on (borrowed); the scenario. Each fault starts at the inner
// frame `at` and lasts `frames` inner frames:
//   kStall        the frames are taken from the inner source and dropped; next()
//                 returns kTimeout once per timeout_ns of the clock meanwhile (a camera
//                 that delivers nothing; a lost HDMI signal)
//   kDisappear    as kStall with error() "device gone", then the device comes back
//                 with its sequence numbers restarting at 0 (a reopened V4L2 node)
//   kCorrupt      delivered with every byte replaced by noise (a fixed LCG: repeatable)
//   kTruncate     delivered with the bottom half of the rows zero (a short transfer)
//   kResize       delivered at width x height (nearest neighbour), announced by
//                 kFormatChange, and again when the original size comes back
//   kPixelFormat  delivered as pixel_format (kYuyv, kGray8 or kBgra32), announced
//                 the same way
// Outputs: frames in capture order; an injected frame is a copy in the decorator's own
// pool (sized in start() for the largest format of the scenario: nothing is allocated
// per frame), its buffer_index kOwnIndex + slot; others are the inner frames as lent.
// dropped_frames() counts the inner frames a stall or disappearance swallowed.
#pragma once

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "endotower/hal/clock.hpp"
#include "endotower/hal/frame_source.hpp"

namespace endotower::sim {

struct CaptureFault {
    enum class Kind { kStall, kDisappear, kCorrupt, kTruncate, kResize, kPixelFormat };
    Kind kind = Kind::kStall;
    std::int64_t at = 0;                                      // inner frame index where it starts
    std::int64_t frames = 1;                                  // how many inner frames it lasts
    int width = 0, height = 0;                                // kResize
    hal::PixelFormat pixel_format = hal::PixelFormat::kYuyv;  // kPixelFormat
};

class FaultInjectingSource final : public hal::FrameSource {
public:
    static constexpr int kOwnIndex = 2000;

    FaultInjectingSource(hal::FrameSource& inner, hal::Clock& clock,
                         std::vector<CaptureFault> scenario);

    bool start() override;
    void stop() override { inner_.stop(); }
    hal::SourceStatus next(hal::Frame& out, hal::Nanos timeout_ns) override;
    void release(const hal::Frame& frame) override;
    hal::FrameFormat format() const override { return format_; }
    hal::Nanos frame_period() const override { return inner_.frame_period(); }
    int buffer_count() const override { return inner_.buffer_count(); }
    const std::string& error() const override { return gone_ ? gone_error_ : inner_.error(); }

    // Inner frames dropped by kStall / kDisappear so far.
    std::int64_t dropped_frames() const { return dropped_; }

private:
    const CaptureFault* fault_at(std::int64_t index) const;
    hal::FrameFormat format_for(const CaptureFault* f) const;
    bool transform(const CaptureFault& f, const hal::Frame& in, hal::Frame& out);

    hal::FrameSource& inner_;
    hal::Clock& clock_;
    std::vector<CaptureFault> scenario_;
    hal::FrameFormat inner_format_{}, format_{};
    std::int64_t index_ = 0, dropped_ = 0;
    std::uint64_t sequence_base_ = 0;  // subtracted after a disappearance
    std::uint32_t noise_ = 12345;
    bool gone_ = false;
    std::string gone_error_ = "simulated capture device gone; reopening";
    std::vector<std::vector<std::uint8_t>> pool_;
    std::vector<bool> borrowed_;
    std::mutex mutex_;  // borrowed_: release() may come from any thread
};

}  // namespace endotower::sim
