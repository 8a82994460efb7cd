// FrameSource: one capture device family (V4L2 camera, recorded file, ...).
//
// Ownership: the source owns a fixed pool of buffers allocated in start(). next()
// lends one as a Frame; the borrower gives it back with release(). release() may be
// called from any thread; next() only from the one capture thread.
#pragma once

#include <string>

#include "endotower/hal/frame.hpp"

namespace endotower::hal {

enum class SourceStatus {
    kFrame,         // a frame was lent
    kTimeout,       // nothing within the timeout; try again (signal lost, stalled)
    kEndOfStream,   // a recording ended (never returned by a live camera)
    kFormatChange,  // the incoming format changed: give back every borrowed frame
                    // (they stay valid until then), read format(), call next() again
    kError,         // unrecoverable; error() says what and where
};

class FrameSource {
public:
    virtual ~FrameSource() = default;

    // Allocates the buffer pool and starts capturing. False on error (see error()).
    virtual bool start() = 0;
    virtual void stop() = 0;

    // Waits up to timeout_ns for the next frame. On kFrame, `out` is filled.
    virtual SourceStatus next(Frame& out, Nanos timeout_ns) = 0;
    virtual void release(const Frame& frame) = 0;

    // The current format (valid after start() and after kFormatChange).
    virtual FrameFormat format() const = 0;
    // Nominal frame period of the stream, for pacing and the default latency.
    virtual Nanos frame_period() const = 0;
    // Number of buffers in the pool: how many frames may be borrowed at once.
    virtual int buffer_count() const = 0;

    // Human-readable description of the last error, naming the device or file.
    virtual const std::string& error() const = 0;
};

}  // namespace endotower::hal
