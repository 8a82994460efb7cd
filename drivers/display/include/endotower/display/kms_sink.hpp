// KmsSink: hal::VideoSink on a monitor through DRM/KMS, GBM, EGL and GLES2.
//
// Video: the frame goes on the CRTC's primary plane. When the frame carries a
// DMABUF (Frame::dmabuf_fd), is the mode's size and the plane takes its format, the
// buffer itself is scanned out (drmPrimeFDToHandle + AddFB2, checked with a
// TEST_ONLY commit); otherwise one CPU pass converts it into an XRGB8888 dumb
// buffer, centred, and the pass is timed (stats()). The capture buffer is given
// back to the source after present() returns; the source must keep at least two
// other buffers queued so a scanned-out one is not refilled before the next flip.
// Overlay: drawn with GLES2 (GlesOverlay) into an ARGB8888 GBM surface of the mode's
// size on an overlay plane (found by its "type" property); an empty overlay turns
// the plane off. A GBM buffer with an invalid modifier is added as plain linear.
// Commits: atomic with a page-flip event (legacy SetCrtc/PageFlip/SetPlane when the
// driver has no atomic API); present() waits for that event and returns its kernel
// timestamp (CLOCK_MONOTONIC). No out-fences are required.
// Hot-unplug: the connector's status, read once a second, or a failed commit or a
// missing flip event (then re-probed) notices the monitor has gone; while
// it is disconnected frames are dropped (present() returns the time of the drop),
// it is probed once a second and the mode is set again when it comes back.
// Writeback (for tests, vkms): with `writeback`, request_readback() makes the next
// present also write the composed picture into a buffer that readback() returns.
// That one commit routes the CRTC to the writeback connector alone (vkms in Linux 6.1
// refuses the monitor and writeback as clones); the next gives it back to the monitor.
// Parameters (defaults): card /dev/dri/card0, connector "" (the first connected),
// mode 1920x1080@60, zero_copy true, atomic true, writeback false.
// Not thread-safe: open() and every later call from one thread (it owns the EGL context).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "endotower/hal/clock.hpp"
#include "endotower/hal/video_sink.hpp"

namespace endotower::display {

struct KmsSinkConfig {
    std::string card = "/dev/dri/card0";
    std::string connector;  // "HDMI-A-1", "Virtual-1", ...; "" = the first connected
    int width = 1920, height = 1080;
    double refresh_hz = 60.0;
    bool zero_copy = true;
    bool atomic = true;
    bool writeback = false;
};

struct KmsSinkStats {
    std::int64_t frames = 0, zero_copy_frames = 0, copied_frames = 0, dropped_frames = 0;
    std::int64_t copy_ns_total = 0, copy_ns_max = 0;        // the CPU pass of the copy path
    std::int64_t overlay_ns_total = 0, overlay_ns_max = 0;  // GLES draw + swap of the overlay
    std::int64_t overlay_frames = 0;
    std::int64_t flip_timeouts = 0, disconnects = 0, reconnects = 0;
};

class KmsSink final : public hal::VideoSink {
public:
    KmsSink(KmsSinkConfig config, hal::Clock& clock);
    ~KmsSink() override;

    // Opens the card, finds connector, mode, CRTC and planes, sets up GBM/EGL. False
    // with error() naming the card or connector and the fix.
    bool open();
    bool configure(const hal::FrameFormat& format) override;
    hal::Nanos present(const hal::Frame& video, const hal::OverlayLayer* overlay,
                       hal::Nanos due_ns) override;
    bool finish() override;
    const std::string& error() const override;

    std::string connector_name() const;
    std::string mode_name() const;  // "1920x1080@60.00"
    hal::Nanos refresh_period() const;
    bool atomic() const;
    bool connected() const;
    const KmsSinkStats& stats() const;

    // Writeback: false when the card has no writeback connector or it was not asked for.
    bool request_readback();
    // Waits for the requested picture; XRGB8888 (bytes B G R X), mode size, or nullptr.
    const std::uint8_t* readback(int& stride, hal::Nanos timeout_ns);

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::display
