// NoSignalSource: a FrameSource decorator that keeps the monitor showing a clear
// "NO SIGNAL" screen while the capture input delivers nothing (cable out, camera off,
// HDMI source changing mode), and passes real frames through untouched otherwise.
//
// Inputs: the inner source (borrowed), the clock. Parameters: after_ns (default:
// 250 ms without a frame before the screen appears).
// Outputs: on an inner timeout past after_ns, a frame of its own buffer (black, the
// words in white in the middle, in the inner source's current format; buffer_index
// kCardIndex, no DMABUF, capture time = now, the last real sequence number). Logs
// once when the signal goes and once when it comes back.
// The card is rendered in start() and after a format change, never per frame; its
// buffer is lent any number of times at once and release() of it is a no-op.
#pragma once

#include <vector>

#include "endotower/app/log.hpp"
#include "endotower/hal/clock.hpp"
#include "endotower/hal/frame_source.hpp"

namespace endotower::app {

class NoSignalSource final : public hal::FrameSource {
public:
    static constexpr int kCardIndex = 1000;

    NoSignalSource(hal::FrameSource& inner, hal::Clock& clock, Log& log, hal::Nanos after_ns = 0);

    bool start() override;
    void stop() override { inner_.stop(); }
    hal::SourceStatus next(hal::Frame& out, hal::Nanos timeout_ns) override;
    void release(const hal::Frame& frame) override;
    hal::FrameFormat format() const override { return inner_.format(); }
    hal::Nanos frame_period() const override { return inner_.frame_period(); }
    int buffer_count() const override { return inner_.buffer_count(); }
    const std::string& error() const override { return inner_.error(); }

    bool showing_card() const { return showing_; }
    // Renders the card for `format` into the own buffer (also used by tests).
    void render(const hal::FrameFormat& format);
    const std::vector<std::uint8_t>& card() const { return card_; }

private:
    hal::FrameSource& inner_;
    hal::Clock& clock_;
    Log& log_;
    hal::Nanos after_ns_;
    hal::Nanos last_frame_ns_ = 0;
    std::uint64_t last_sequence_ = 0;
    bool showing_ = false;
    hal::FrameFormat card_format_{};
    std::vector<std::uint8_t> card_;
};

}  // namespace endotower::app
