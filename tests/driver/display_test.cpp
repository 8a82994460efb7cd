// KmsSink against the real vkms driver (in the qemu guest, vkms loaded with
// enable_overlay=1): frames with an overlay are shown and read back through the
// writeback connector; page-flip timestamps; DMABUF import; the legacy API; the
// monitor unplugged and plugged back (the connector's sysfs `status` forced "off",
// then "detect": the DRM core's own way of faking a hotplug, vkms has no other).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "endotower/display/kms_sink.hpp"
#include "endotower/system/monotonic_clock.hpp"

namespace endotower::display {
namespace {

constexpr int kW = 1920, kH = 1080;

KmsSinkConfig vkms_config() {
    KmsSinkConfig c;
    c.card = "/dev/dri/card0";
    c.connector = "Virtual-1";
    c.writeback = true;
    return c;
}

struct Image {
    std::vector<std::uint8_t> px;
    hal::Frame frame;
    Image(int w, int h, hal::PixelFormat f) {
        frame.format = {w, h, w * hal::bytes_per_pixel(f), f};
        px.assign(frame.format.size_bytes(), 0);
        frame.data = px.data();
        frame.buffer_index = 0;
    }
};

struct Overlay {
    std::vector<std::uint8_t> px;
    hal::OverlayLayer layer;
    Overlay() {
        layer.width = kW;
        layer.height = kH;
        layer.stride = 4 * kW;
        px.assign(static_cast<std::size_t>(layer.stride) * kH, 0);
        layer.rgba = px.data();
    }
    void fill(hal::Rect r, std::uint8_t R, std::uint8_t G, std::uint8_t B, std::uint8_t A) {
        for (int y = r.y; y < r.y + r.height; ++y)
            for (int x = r.x; x < r.x + r.width; ++x) {
                std::uint8_t* p = &px[static_cast<std::size_t>(y) * layer.stride + 4 * x];
                p[0] = R, p[1] = G, p[2] = B, p[3] = A;
            }
        layer.rects[layer.rect_count++] = r;
    }
};

// An XRGB8888 dumb buffer of vkms exported as a DMABUF: a frame the way a capture
// driver hands it over, filled with one colour.
struct DumbDmabuf {
    int fd = -1, dmabuf = -1;
    drm_mode_create_dumb c{};
    std::uint8_t* map = nullptr;
    hal::Frame frame;
    bool create(std::uint8_t b, std::uint8_t g, std::uint8_t r) {
        fd = open("/dev/dri/card0", O_RDWR | O_CLOEXEC);
        c.width = kW, c.height = kH, c.bpp = 32;
        if (fd < 0 || drmIoctl(fd, DRM_IOCTL_MODE_CREATE_DUMB, &c) != 0) return false;
        drm_mode_map_dumb m{};
        m.handle = c.handle;
        if (drmIoctl(fd, DRM_IOCTL_MODE_MAP_DUMB, &m) != 0) return false;
        void* p = mmap(nullptr, c.size, PROT_READ | PROT_WRITE, MAP_SHARED, fd,
                       static_cast<off_t>(m.offset));
        if (p == MAP_FAILED) return false;
        map = static_cast<std::uint8_t*>(p);
        for (std::size_t i = 0; i < c.size; i += 4)
            map[i] = b, map[i + 1] = g, map[i + 2] = r, map[i + 3] = 255;
        if (drmPrimeHandleToFD(fd, c.handle, DRM_CLOEXEC | DRM_RDWR, &dmabuf) != 0) return false;
        frame.format = {kW, kH, static_cast<int>(c.pitch), hal::PixelFormat::kBgra32};
        frame.data = map;
        frame.buffer_index = 3;
        frame.dmabuf_fd = dmabuf;
        return true;
    }
    ~DumbDmabuf() {
        if (dmabuf >= 0) close(dmabuf);
        if (map != nullptr) munmap(map, c.size);
        if (fd >= 0) close(fd);
    }
};

// B G R of the written-back picture at (x, y).
const std::uint8_t* px_at(const std::uint8_t* wb, int stride, int x, int y) {
    return wb + static_cast<std::ptrdiff_t>(y) * stride + 4 * x;
}

// Shows `frame` (and `overlay`) with the writeback connector attached and returns the
// picture written back, or nullptr when none came within 5 s.
// vkms switches its composer on in a writeback commit and off in the job's clean-up,
// a workqueue item that runs after the picture is signalled; the switch is a flag, not
// a count. A writeback committed before the previous job's clean-up ran is then never
// composed (its fence never signals), and the extra vblank reference dropped can stop
// the vblank timer that page flips wait for. On a loaded emulated CPU the clean-up can
// come late, so each picture is followed by a pause long enough for it.
const std::uint8_t* show_and_read_back(KmsSink& sink, const hal::Frame& frame,
                                       const hal::OverlayLayer* overlay, hal::Clock& clock,
                                       int& stride) {
    if (!sink.request_readback() || sink.present(frame, overlay, clock.now()) <= 0) return nullptr;
    const std::uint8_t* wb = sink.readback(stride, 5 * hal::kSecond);
    usleep(500'000);
    return wb;
}

class DisplayTest : public ::testing::Test {
protected:
    void SetUp() override {
        if (access("/dev/dri/card0", F_OK) != 0)
            GTEST_SKIP() << "no /dev/dri/card0: run in the guest with vkms";
    }
    system::MonotonicClock clock_;
};

// Forces the vkms connector's status through sysfs ("off", "detect").
bool force_status(const char* value) {
    std::ofstream f("/sys/class/drm/card0-Virtual-1/status");
    f << value;
    f.flush();
    return static_cast<bool>(f);
}

// Unplugged while showing video: the sink notices within its once-a-second status
// read, drops frames without blocking or failing, and when the monitor is back sets
// the mode again and flips on the vblank grid as before.
TEST_F(DisplayTest, MonitorUnpluggedAndPluggedBack) {
    KmsSinkConfig c = vkms_config();
    c.writeback = false;
    KmsSink sink(c, clock_);
    ASSERT_TRUE(sink.open()) << sink.error();
    Image img(kW, kH, hal::PixelFormat::kBgra32);
    ASSERT_TRUE(sink.configure(img.frame.format));
    for (int i = 0; i < 5; ++i)
        ASSERT_GT(sink.present(img.frame, nullptr, clock_.now()), 0) << sink.error();
    ASSERT_TRUE(force_status("off"));
    // At 60 Hz the status read comes within 61 presents; while unplugged present()
    // returns at once (no flip to wait for), so allow many more calls.
    int until_noticed = 0;
    while (sink.connected() && until_noticed < 200) {
        ASSERT_GT(sink.present(img.frame, nullptr, clock_.now()), 0) << sink.error();
        ++until_noticed;
    }
    EXPECT_FALSE(sink.connected());
    EXPECT_EQ(sink.stats().disconnects, 1);
    const std::int64_t dropped = sink.stats().dropped_frames;
    EXPECT_GE(dropped, 1);
    for (int i = 0; i < 20; ++i) ASSERT_GT(sink.present(img.frame, nullptr, clock_.now()), 0);
    EXPECT_EQ(sink.stats().dropped_frames, dropped + 20);
    ASSERT_TRUE(force_status("detect"));
    // Probed once a second while unplugged: back within about a second of presents.
    const hal::Nanos t_back = clock_.now();
    std::int64_t calls = 0;
    while (!sink.connected() && clock_.now() - t_back < 5 * hal::kSecond) {
        ++calls;
        ASSERT_GT(sink.present(img.frame, nullptr, clock_.now()), 0);
        usleep(10000);
    }
    ASSERT_TRUE(sink.connected());
    EXPECT_EQ(sink.stats().reconnects, 1);
    const double period = static_cast<double>(sink.refresh_period());
    std::vector<hal::Nanos> t;
    for (int i = 0; i < 10; ++i) t.push_back(sink.present(img.frame, nullptr, clock_.now()));
    for (std::size_t i = 2; i < t.size(); ++i) {
        const double steps = static_cast<double>(t[i] - t[i - 1]) / period;
        ASSERT_GE(steps, 0.5) << "flip " << i;
        EXPECT_NEAR(steps, std::round(steps), 0.02) << "flip " << i << " off the vblank grid";
    }
    // Every present while unplugged was dropped, the one that found the monitor back was not.
    EXPECT_EQ(sink.stats().dropped_frames, dropped + 20 + calls - 1);
}

TEST_F(DisplayTest, OpensVirtualConnectorAtTheBoardMode) {
    KmsSink sink(vkms_config(), clock_);
    ASSERT_TRUE(sink.open()) << sink.error();
    EXPECT_EQ(sink.connector_name(), "Virtual-1");
    EXPECT_EQ(sink.mode_name(), "1920x1080@60.00");
    EXPECT_TRUE(sink.atomic());
}

TEST_F(DisplayTest, UnknownConnectorNamesTheChoices) {
    KmsSinkConfig c = vkms_config();
    c.connector = "HDMI-A-7";
    KmsSink sink(c, clock_);
    EXPECT_FALSE(sink.open());
    EXPECT_NE(sink.error().find("no connector named 'HDMI-A-7'"), std::string::npos)
        << sink.error();
    EXPECT_NE(sink.error().find("Virtual-1 (connected)"), std::string::npos) << sink.error();
}

TEST_F(DisplayTest, MissingModeListsTheModes) {
    KmsSinkConfig c = vkms_config();
    c.width = 1234;
    KmsSink sink(c, clock_);
    EXPECT_FALSE(sink.open());
    EXPECT_NE(sink.error().find("has no mode 1234x1080@60.00"), std::string::npos) << sink.error();
}

// A BGRA frame smaller than the mode (copy path, centred) with an opaque and a
// half-transparent overlay rect: the written-back picture, pixel by pixel.
TEST_F(DisplayTest, FrameAndOverlayReadBackThroughWriteback) {
    KmsSink sink(vkms_config(), clock_);
    ASSERT_TRUE(sink.open()) << sink.error();
    Image img(1280, 720, hal::PixelFormat::kBgra32);
    for (int y = 0; y < 720; ++y)
        for (int x = 0; x < 1280; ++x) {
            std::uint8_t* p = &img.px[static_cast<std::size_t>(y) * 1280 * 4 + 4 * x];
            p[0] = static_cast<std::uint8_t>(x), p[1] = static_cast<std::uint8_t>(y), p[2] = 77,
            p[3] = 255;
        }
    ASSERT_TRUE(sink.configure(img.frame.format)) << sink.error();
    Overlay ov;
    ov.fill({100, 50, 40, 30}, 255, 0, 0, 255);   // opaque red, over the black border
    ov.fill({700, 500, 20, 10}, 0, 0, 255, 128);  // half blue over the frame
    int stride = 0;
    const std::uint8_t* wb = show_and_read_back(sink, img.frame, &ov.layer, clock_, stride);
    ASSERT_NE(wb, nullptr) << "no writeback picture; " << sink.error();
    const int ox = (kW - 1280) / 2, oy = (kH - 720) / 2;
    // The video, bit exact, away from the overlay.
    for (int y : {0, 1, 359, 719})
        for (int x : {0, 1, 255, 640, 1279}) {
            const std::uint8_t* p = px_at(wb, stride, ox + x, oy + y);
            ASSERT_EQ(p[0], static_cast<std::uint8_t>(x)) << x << "," << y;
            ASSERT_EQ(p[1], static_cast<std::uint8_t>(y)) << x << "," << y;
            ASSERT_EQ(p[2], 77) << x << "," << y;
        }
    // Black around the smaller frame.
    for (int c = 0; c < 3; ++c) EXPECT_EQ(px_at(wb, stride, 5, 5)[c], 0);
    // The opaque overlay, exact, upright (row 50 is near the top).
    for (int y = 50; y < 80; ++y)
        for (int x = 100; x < 140; ++x) {
            const std::uint8_t* p = px_at(wb, stride, x, y);
            ASSERT_EQ(p[2], 255) << x << "," << y;
            ASSERT_EQ(p[1], 0) << x << "," << y;
            ASSERT_EQ(p[0], 0) << x << "," << y;
        }
    EXPECT_EQ(px_at(wb, stride, 99, 50)[2], 0);
    EXPECT_EQ(px_at(wb, stride, 100, 80)[2], 0);
    // Half blue over the frame: blue ~ 128 + under * (1 - a), green ~ under * (1 - a).
    const std::uint8_t* p = px_at(wb, stride, 705, 505);
    EXPECT_NEAR(p[1], (505 - oy) % 256 * 127 / 255.0, 2);
    EXPECT_NEAR(p[0], 128 + (705 - ox) % 256 * 127 / 255.0, 2);
    EXPECT_NEAR(p[2], 77 * 127 / 255.0, 2);
}

// The copy path converts YUYV: limited-range white and black.
TEST_F(DisplayTest, YuyvFrameIsConvertedOnce) {
    KmsSink sink(vkms_config(), clock_);
    ASSERT_TRUE(sink.open()) << sink.error();
    Image img(kW, kH, hal::PixelFormat::kYuyv);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; x += 2) {
            std::uint8_t* q = &img.px[static_cast<std::size_t>(y) * kW * 2 + 2 * x];
            const std::uint8_t luma = x < kW / 2 ? 235 : 16;
            q[0] = luma, q[1] = 128, q[2] = luma, q[3] = 128;
        }
    ASSERT_TRUE(sink.configure(img.frame.format)) << sink.error();
    int stride = 0;
    const std::uint8_t* wb = show_and_read_back(sink, img.frame, nullptr, clock_, stride);
    ASSERT_NE(wb, nullptr) << "no writeback picture; " << sink.error();
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(px_at(wb, stride, 100, 100)[c], 255, 1);
        EXPECT_NEAR(px_at(wb, stride, kW - 100, 100)[c], 0, 1);
    }
    EXPECT_EQ(sink.stats().copied_frames, 1);
    EXPECT_EQ(sink.stats().zero_copy_frames, 0);
}

// Back-to-back presents flip on consecutive vblanks: the kernel timestamps step by
// one refresh period (a whole number of periods when the emulated CPU falls behind).
TEST_F(DisplayTest, PageFlipTimestampsStepByOnePeriod) {
    KmsSinkConfig c = vkms_config();
    c.writeback = false;
    KmsSink sink(c, clock_);
    ASSERT_TRUE(sink.open()) << sink.error();
    // Zero copy and no overlay: the least work per frame, so that the emulated CPU
    // keeps up with the refresh rate.
    DumbDmabuf buf;
    ASSERT_TRUE(buf.create(1, 2, 3));
    ASSERT_TRUE(sink.configure(buf.frame.format));
    const double period = static_cast<double>(sink.refresh_period());
    ASSERT_NEAR(period, 1e9 / 60.0, 1e4);
    std::vector<hal::Nanos> t;
    for (int i = 0; i < 40; ++i) {
        const hal::Nanos before = clock_.now();
        const hal::Nanos flip = sink.present(buf.frame, nullptr, before);
        ASSERT_GT(flip, 0) << sink.error();
        // The flip is a CLOCK_MONOTONIC time between the commit and now.
        EXPECT_GE(flip, before - static_cast<hal::Nanos>(period));
        EXPECT_LE(flip, clock_.now());
        t.push_back(flip);
    }
    // The first flip is the mode set, which restarts the vblank timer.
    int single = 0;
    for (std::size_t i = 2; i < t.size(); ++i) {
        const double steps = static_cast<double>(t[i] - t[i - 1]) / period;
        ASSERT_GE(steps, 0.5) << "flip " << i << " not after the previous one";
        EXPECT_NEAR(steps, std::round(steps), 0.02) << "flip " << i << " off the vblank grid";
        single += std::lround(steps) == 1;
    }
    // How many vblanks each present takes depends on the emulated CPU's load; that
    // back-to-back presents can land on consecutive vblanks does not.
    EXPECT_GE(single, 1) << "no two flips on consecutive vblanks";
}

// A frame that arrives as a DMABUF of the mode's size in a format the primary plane
// takes is scanned out without a copy (here the DMABUF of a dumb buffer).
TEST_F(DisplayTest, DmabufFrameIsScannedOutWithoutCopy) {
    KmsSink sink(vkms_config(), clock_);
    ASSERT_TRUE(sink.open()) << sink.error();
    DumbDmabuf buf;
    ASSERT_TRUE(buf.create(10, 20, 30));
    ASSERT_TRUE(sink.configure(buf.frame.format)) << sink.error();
    for (int i = 0; i < 3; ++i) {
        int stride = 0;
        const std::uint8_t* wb = show_and_read_back(sink, buf.frame, nullptr, clock_, stride);
        ASSERT_NE(wb, nullptr) << "no writeback picture " << i << "; " << sink.error();
        EXPECT_EQ(px_at(wb, stride, 960, 540)[0], 10);
        EXPECT_EQ(px_at(wb, stride, 960, 540)[1], 20);
        EXPECT_EQ(px_at(wb, stride, 960, 540)[2], 30);
    }
    EXPECT_EQ(sink.stats().zero_copy_frames, 3);
    EXPECT_EQ(sink.stats().copied_frames, 0);
}

TEST_F(DisplayTest, LegacyPageFlipFallback) {
    KmsSinkConfig c = vkms_config();
    c.atomic = false;
    c.writeback = false;
    KmsSink sink(c, clock_);
    ASSERT_TRUE(sink.open()) << sink.error();
    EXPECT_FALSE(sink.atomic());
    Image img(kW, kH, hal::PixelFormat::kBgra32);
    ASSERT_TRUE(sink.configure(img.frame.format));
    Overlay ov;
    ov.fill({0, 0, 64, 64}, 0, 255, 0, 255);
    hal::Nanos last = 0;
    for (int i = 0; i < 5; ++i) {
        const hal::Nanos t = sink.present(img.frame, i % 2 ? &ov.layer : nullptr, clock_.now());
        ASSERT_GT(t, last) << sink.error();
        last = t;
    }
}

}  // namespace
}  // namespace endotower::display
