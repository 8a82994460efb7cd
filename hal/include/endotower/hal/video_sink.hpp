// VideoSink: where the composed picture goes (the HDMI monitor through KMS, or a
// file in simulation).
//
// The sink composes two layers: the video frame, untouched, and an RGBA overlay
// above it. Outside the overlay's non-transparent pixels the output equals the
// input bit for bit. Both layers are borrowed for the call only.
#pragma once

#include <string>

#include "endotower/hal/frame.hpp"
#include "endotower/hal/overlay.hpp"

namespace endotower::hal {

class VideoSink {
public:
    virtual ~VideoSink() = default;

    // (Re)configures for a video format; called before the first frame and on
    // every format change. False on error (see error()).
    virtual bool configure(const FrameFormat& format) = 0;

    // Shows `video` with `overlay` (nullptr: video only) at time `due_ns`.
    // Returns the time the picture was actually presented (the page-flip time on a
    // display), or a negative value on error.
    virtual Nanos present(const Frame& video, const OverlayLayer* overlay, Nanos due_ns) = 0;

    // Flushes and closes whatever was written; false if that failed.
    virtual bool finish() = 0;

    virtual const std::string& error() const = 0;
};

}  // namespace endotower::hal
