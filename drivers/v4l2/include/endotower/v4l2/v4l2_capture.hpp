// V4l2Capture: a V4L2 video-capture device as a hal::FrameSource (streaming I/O,
// single- or multi-planar API as the device offers, one-buffer formats; MMAP buffers,
// each also exported as a DMABUF for the display).
//
// Parameters (board file `capture:`): device path, format (yuyv|uyvy|nv12|bgrx|mjpeg),
// width/height (ignored when DV timings set them), fps (VIDIOC_S_PARM; 0 = leave),
// buffers (default 4: two queued in the driver so a frame is always being filled, one
// on screen, one being composed; more buffers only add frames that could wait), input
// (VIDIOC_S_INPUT, -1 = leave), dv_timings ("" = leave, "query" = what the receiver
// detects, or a name like "1920x1080p60").
//
// MJPEG: next() decodes the buffer (MjpegDecoder) into a BGR24 frame of this object's,
// one per buffer (allocated at start and at a format change), and lends that frame
// (dmabuf_fd -1; the buffers are not exported). A buffer that does not decode is
// requeued like one the driver flags V4L2_BUF_FLAG_ERROR: counted in stats().corrupt,
// error() names the device and the buffer sequence, and next() goes on waiting.
//
// next() always hands out the newest completed frame: older ones found ready at the
// same time are requeued (counted in skipped) so no frame waits behind another.
// capture_ns is the kernel's buffer timestamp (CLOCK_MONOTONIC); sequence is the
// driver's, and its gaps are counted as drops.
// V4L2_EVENT_SOURCE_CHANGE: new timings -> kFormatChange (the stream restarts at the
// next next() once every frame is given back); no signal -> kTimeout until it
// returns. Device gone (ENODEV, POLLERR) -> kTimeout while next() tries to reopen the
// path, at most once per call. Errors name the device, the ioctl and errno.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "endotower/hal/frame_source.hpp"
#include "endotower/v4l2/capture_format.hpp"

namespace endotower::v4l2 {

struct V4l2CaptureConfig {
    std::string device = "/dev/video0";
    CaptureFormat format = CaptureFormat::kYuyv;
    int width = 1920;
    int height = 1080;
    double fps = 0.0;
    int buffers = 4;
    int input = -1;
    std::string dv_timings;
};

struct CaptureStats {
    std::uint64_t frames = 0;   // handed out by next()
    std::uint64_t drops = 0;    // sequence gaps (the driver had no free buffer)
    std::uint64_t skipped = 0;  // completed but superseded by a newer frame in next()
    std::uint64_t timeouts = 0;
    std::uint64_t format_changes = 0;
    std::uint64_t reopens = 0;  // successful reopens after the device went away
    std::uint64_t corrupt = 0;  // flagged V4L2_BUF_FLAG_ERROR, or MJPEG that did not decode
    bool signal = false;        // false while the source reports no signal
    bool present = false;       // false while the device node is gone
};

class V4l2Capture final : public hal::FrameSource {
public:
    explicit V4l2Capture(V4l2CaptureConfig config);
    ~V4l2Capture() override;

    bool start() override;
    void stop() override;
    hal::SourceStatus next(hal::Frame& out, hal::Nanos timeout_ns) override;
    void release(const hal::Frame& frame) override;
    hal::FrameFormat format() const override;
    hal::Nanos frame_period() const override;
    int buffer_count() const override;
    const std::string& error() const override;

    // The DMABUF fd of buffer `index` (owned here, valid until stop() or a format
    // change), or -1 when the driver cannot export.
    int dmabuf_fd(int index) const;
    const CaptureStats& stats() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::v4l2
