// V4l2Capture against the kernel's vivid driver in the qemu guest: its HDMI input
// (input 3) at 1920x1080p60 YUYV. Frames, sequence numbers and kernel timestamps;
// drops (vivid's percentage_of_dropped_buffers); no signal and back; a format change
// from the source (V4L2_EVENT_SOURCE_CHANGE); the device unbound and bound again.
// vivid's second instance (/dev/video2) speaks only the multi-planar API, as HDMI
// receivers like RK3588's hdmirx do.
#include <gtest/gtest.h>
#include <time.h>

#include <cstdlib>
#include <string>
#include <tuple>
#include <vector>

#include "endotower/v4l2/v4l2_capture.hpp"

namespace endotower::v4l2 {
namespace {

constexpr hal::Nanos kPeriod1080p60 = 16'666'667;  // 148.5 MHz / (2200 x 1125)

hal::Nanos now_ns() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * hal::kSecond + ts.tv_nsec;
}

void ctl(const std::string& args) {
    const std::string cmd = "v4l2-ctl -d /dev/video0 " + args + " >/dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

V4l2CaptureConfig hdmi_1080p60() {
    V4l2CaptureConfig c;
    c.device = "/dev/video0";
    c.format = CaptureFormat::kYuyv;
    c.input = 3;
    c.dv_timings = "1920x1080p60";
    return c;
}

class V4l2Guest : public ::testing::Test {
protected:
    void SetUp() override {
        // Every test starts from a steady source: signal, no artificial drops.
        ctl("-i 3 -c dv_timings_signal_mode=0 -c percentage_of_dropped_buffers=0");
    }
};

// Waits for a frame through timeouts (up to `tries` of 1 s each).
hal::SourceStatus next_not_timeout(V4l2Capture& cap, hal::Frame& f, int tries = 10) {
    hal::SourceStatus s = hal::SourceStatus::kTimeout;
    for (int i = 0; i < tries && s == hal::SourceStatus::kTimeout; ++i)
        s = cap.next(f, hal::kSecond);
    return s;
}

TEST_F(V4l2Guest, Captures1080p60YuyvWithSequenceAndMonotonicTimestamps) {
    V4l2Capture cap(hdmi_1080p60());
    const hal::Nanos t_start = now_ns();
    ASSERT_TRUE(cap.start()) << cap.error();
    EXPECT_EQ(cap.format(), (hal::FrameFormat{1920, 1080, 3840, hal::PixelFormat::kYuyv}));
    EXPECT_NEAR(static_cast<double>(cap.frame_period()), kPeriod1080p60, 1.0);
    EXPECT_EQ(cap.buffer_count(), 4);
    for (int i = 0; i < cap.buffer_count(); ++i) EXPECT_GE(cap.dmabuf_fd(i), 0) << "buffer " << i;

    constexpr int kFrames = 100;
    std::vector<hal::Frame> frames;
    std::uint64_t gaps = 0;
    for (int i = 0; i < kFrames; ++i) {
        hal::Frame f;
        ASSERT_EQ(next_not_timeout(cap, f), hal::SourceStatus::kFrame) << cap.error();
        const hal::Nanos received = now_ns();
        EXPECT_EQ(f.format, cap.format());
        ASSERT_NE(f.data, nullptr);
        EXPECT_GE(f.buffer_index, 0);
        EXPECT_LT(f.buffer_index, 4);
        // The kernel stamps on CLOCK_MONOTONIC. vivid stamps the ideal end of frame
        // (start + (n + 1) periods), which may be up to a period after it delivers.
        EXPECT_GT(f.capture_ns, t_start);
        EXPECT_LE(f.capture_ns, received + kPeriod1080p60);
        if (!frames.empty()) {
            EXPECT_GT(f.sequence, frames.back().sequence);
            EXPECT_GT(f.capture_ns, frames.back().capture_ns);
            gaps += f.sequence - frames.back().sequence - 1;
        }
        if (i == kFrames / 2) {
            // vivid's 75 % colour bars: the first bar is 75 % white, Y 180, U = V = 128
            // (BT.709 limited range), at mid-height where no text is drawn.
            const std::uint8_t* px = f.data + 540 * f.format.stride + 2 * 60;
            EXPECT_NEAR(px[0], 180, 3);
            EXPECT_NEAR(px[1], 128, 3);
            EXPECT_NEAR(px[3], 128, 3);
        }
        frames.push_back(f);
        cap.release(f);
    }
    const CaptureStats& s = cap.stats();
    EXPECT_EQ(s.frames, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(s.drops, gaps);  // every sequence gap is counted, nothing else
    // vivid stamps frame n at start + n periods: the spread of kernel timestamps
    // over the sequence span is one frame period (to within 2 %).
    const double per_seq =
        static_cast<double>(frames.back().capture_ns - frames.front().capture_ns) /
        static_cast<double>(frames.back().sequence - frames.front().sequence);
    EXPECT_NEAR(per_seq, kPeriod1080p60, 0.02 * kPeriod1080p60);
    std::printf("captured %d frames, %llu dropped by the driver, %llu skipped for newer ones\n",
                kFrames, static_cast<unsigned long long>(s.drops),
                static_cast<unsigned long long>(s.skipped));
}

TEST_F(V4l2Guest, DroppedBuffersAreCountedFromSequenceGaps) {
    ctl("-c percentage_of_dropped_buffers=50");
    V4l2Capture cap(hdmi_1080p60());
    ASSERT_TRUE(cap.start()) << cap.error();
    std::uint64_t first = 0, last = 0, gaps = 0, drops_before = 0;
    for (int i = 0; i < 40; ++i) {
        hal::Frame f;
        ASSERT_EQ(next_not_timeout(cap, f), hal::SourceStatus::kFrame) << cap.error();
        if (i == 0) {
            first = f.sequence;
            // Buffers vivid dropped before the first one handed out count too.
            drops_before = cap.stats().drops;
        } else {
            gaps += f.sequence - last - 1;
        }
        last = f.sequence;
        cap.release(f);
    }
    EXPECT_GT(gaps, 0u);
    EXPECT_EQ(cap.stats().drops - drops_before, gaps);
    EXPECT_EQ(last - first + 1, 40 + gaps);
}

TEST_F(V4l2Guest, NoSignalGivesTimeoutsAndCaptureResumes) {
    V4l2Capture cap(hdmi_1080p60());
    ASSERT_TRUE(cap.start()) << cap.error();
    hal::Frame f;
    ASSERT_EQ(next_not_timeout(cap, f), hal::SourceStatus::kFrame);
    cap.release(f);
    ctl("-c dv_timings_signal_mode=1");  // "No Signal"
    int timeouts = 0;
    for (int i = 0; i < 20 && timeouts < 3; ++i) {
        const hal::SourceStatus s = cap.next(f, 200 * hal::kMillisecond);
        if (s == hal::SourceStatus::kFrame) cap.release(f);
        if (s == hal::SourceStatus::kTimeout) ++timeouts;
        ASSERT_NE(s, hal::SourceStatus::kError) << cap.error();
    }
    EXPECT_EQ(timeouts, 3);
    EXPECT_FALSE(cap.stats().signal);
    ctl("-c dv_timings_signal_mode=0");
    ASSERT_EQ(next_not_timeout(cap, f), hal::SourceStatus::kFrame) << cap.error();
    EXPECT_TRUE(cap.stats().signal);
    EXPECT_EQ(f.format.width, 1920);
    cap.release(f);
}

// Started while the receiver has no signal (fixed timings are set all the same): no
// frame of the receiver's noise, timeouts until the signal comes.
TEST_F(V4l2Guest, StartedWithoutASignalGivesTimeoutsUntilItComes) {
    ctl("-c dv_timings_signal_mode=1");  // "No Signal"
    V4l2Capture cap(hdmi_1080p60());
    ASSERT_TRUE(cap.start()) << cap.error();
    EXPECT_FALSE(cap.stats().signal);
    hal::Frame f;
    for (int i = 0; i < 5; ++i)
        ASSERT_EQ(cap.next(f, 200 * hal::kMillisecond), hal::SourceStatus::kTimeout)
            << "a frame at call " << i << " while there is no signal";
    ctl("-c dv_timings_signal_mode=0");
    ASSERT_EQ(next_not_timeout(cap, f), hal::SourceStatus::kFrame) << cap.error();
    EXPECT_TRUE(cap.stats().signal);
    EXPECT_EQ(f.format.width, 1920);
    cap.release(f);
}

TEST_F(V4l2Guest, SourceFormatChangeRestartsAtTheNewSize) {
    V4l2Capture cap(hdmi_1080p60());
    ASSERT_TRUE(cap.start()) << cap.error();
    hal::Frame f;
    ASSERT_EQ(next_not_timeout(cap, f), hal::SourceStatus::kFrame);
    // Keep this frame borrowed across the change: it stays valid until given back.
    ctl("-c dv_timings=9 -c dv_timings_signal_mode=4");  // "Selected DV Timings": 1280x720p60
    hal::SourceStatus s = hal::SourceStatus::kTimeout;
    hal::Frame g;
    for (int i = 0; i < 20 && s != hal::SourceStatus::kFormatChange; ++i) {
        s = cap.next(g, 500 * hal::kMillisecond);
        if (s == hal::SourceStatus::kFrame) cap.release(g);
    }
    ASSERT_EQ(s, hal::SourceStatus::kFormatChange);
    EXPECT_EQ(f.data[0], f.data[0]);  // still mapped (ASan/segfault would say otherwise)
    cap.release(f);
    for (int i = 0; i < 10 && s != hal::SourceStatus::kFrame; ++i) s = cap.next(g, hal::kSecond);
    ASSERT_EQ(s, hal::SourceStatus::kFrame) << cap.error();
    EXPECT_EQ(cap.format(), (hal::FrameFormat{1280, 720, 2560, hal::PixelFormat::kYuyv}));
    EXPECT_EQ(g.format, cap.format());
    EXPECT_GE(cap.stats().format_changes, 1u);
    cap.release(g);
}

TEST_F(V4l2Guest, DeviceUnboundThenBoundIsReopened) {
    V4l2Capture cap(hdmi_1080p60());
    ASSERT_TRUE(cap.start()) << cap.error();
    hal::Frame f;
    ASSERT_EQ(next_not_timeout(cap, f), hal::SourceStatus::kFrame);
    cap.release(f);
    ASSERT_EQ(std::system("echo vivid.0 > /sys/bus/platform/drivers/vivid/unbind"), 0);
    hal::SourceStatus s = hal::SourceStatus::kFrame;
    for (int i = 0; i < 20 && (s == hal::SourceStatus::kFrame || cap.stats().present); ++i) {
        s = cap.next(f, 200 * hal::kMillisecond);
        if (s == hal::SourceStatus::kFrame) cap.release(f);
    }
    EXPECT_EQ(s, hal::SourceStatus::kTimeout);
    EXPECT_FALSE(cap.stats().present);
    EXPECT_EQ(cap.next(f, 50 * hal::kMillisecond), hal::SourceStatus::kTimeout);  // still gone
    EXPECT_NE(cap.error().find("/dev/video0"), std::string::npos) << cap.error();
    ASSERT_EQ(std::system("echo vivid.0 > /sys/bus/platform/drivers/vivid/bind"), 0);
    for (int i = 0; i < 50 && s != hal::SourceStatus::kFrame; ++i) {
        s = cap.next(f, 200 * hal::kMillisecond);
        if (s == hal::SourceStatus::kFormatChange) continue;
    }
    ASSERT_EQ(s, hal::SourceStatus::kFrame) << cap.error();
    EXPECT_EQ(f.format.width, 1920);
    EXPECT_TRUE(cap.stats().present);
    EXPECT_EQ(cap.stats().reopens, 1u);
    cap.release(f);
}

// The multi-planar API with one-buffer formats: YUYV and NV12 frames as from the
// single-planar device, with sequence numbers, kernel timestamps and DMABUF export.
TEST(V4l2GuestMplane, CapturesThroughTheMultiPlanarApi) {
    ASSERT_EQ(std::system("v4l2-ctl -d /dev/video2 -i 3 -c dv_timings_signal_mode=0 >/dev/null"),
              0);
    for (const auto& [format, pixel, stride] :
         {std::tuple{CaptureFormat::kYuyv, hal::PixelFormat::kYuyv, 3840},
          std::tuple{CaptureFormat::kNv12, hal::PixelFormat::kNv12, 1920}}) {
        V4l2CaptureConfig c = hdmi_1080p60();
        c.device = "/dev/video2";
        c.format = format;
        V4l2Capture cap(c);
        ASSERT_TRUE(cap.start()) << cap.error();
        EXPECT_EQ(cap.format(), (hal::FrameFormat{1920, 1080, stride, pixel}));
        std::uint64_t last = 0;
        hal::Nanos last_t = 0;
        for (int i = 0; i < 20; ++i) {
            hal::Frame f;
            ASSERT_EQ(next_not_timeout(cap, f), hal::SourceStatus::kFrame) << cap.error();
            ASSERT_NE(f.data, nullptr);
            EXPECT_GE(f.dmabuf_fd, 0);
            if (i > 0) {
                EXPECT_GT(f.sequence, last);
                EXPECT_GT(f.capture_ns, last_t);
            }
            last = f.sequence;
            last_t = f.capture_ns;
            // vivid's colour bars: the picture is not blank.
            int distinct = 0;
            for (int x = 1; x < 1920; x += 97) distinct += f.data[x * 2] != f.data[0];
            EXPECT_GT(distinct, 3);
            cap.release(f);
        }
        EXPECT_LE(std::llabs(static_cast<long long>(last_t - now_ns())), 5 * hal::kSecond);
        cap.stop();
    }
}

TEST(V4l2GuestErrors, ClearMessagesForBadConfiguration) {
    V4l2CaptureConfig c = hdmi_1080p60();
    c.format = CaptureFormat::kMjpeg;  // vivid offers no MJPEG (tests/unit/v4l2 decodes it)
    V4l2Capture mjpeg(c);
    EXPECT_FALSE(mjpeg.start());
    EXPECT_EQ(mjpeg.error().rfind("/dev/video0: does not offer MJPG (it chose ", 0), 0u)
        << mjpeg.error();

    c = hdmi_1080p60();
    c.device = "/dev/video9";
    V4l2Capture missing(c);
    EXPECT_FALSE(missing.start());
    EXPECT_EQ(missing.error(), "open(/dev/video9): No such file or directory (errno 2)");

    c = hdmi_1080p60();
    c.device = "/dev/video1";  // vivid's video output node
    V4l2Capture output(c);
    EXPECT_FALSE(output.start());
    EXPECT_NE(output.error().find("/dev/video1: not a streaming video capture device"),
              std::string::npos)
        << output.error();

    c = hdmi_1080p60();
    c.dv_timings = "1921x1080p60";
    V4l2Capture timings(c);
    EXPECT_FALSE(timings.start());
    EXPECT_NE(timings.error().find("lists no DV timings 1921x1080p60"), std::string::npos)
        << timings.error();
}

}  // namespace
}  // namespace endotower::v4l2
