// The V4L2 format table and DV-timings names (no device needed).
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include "endotower/v4l2/capture_format.hpp"

namespace endotower::v4l2 {
namespace {

TEST(CaptureFormat, NamesFourccsAndPipelineFormats) {
    CaptureFormat f{};
    ASSERT_TRUE(parse_capture_format("yuyv", f));
    EXPECT_EQ(info(f).fourcc, V4L2_PIX_FMT_YUYV);
    EXPECT_EQ(info(f).pixel, hal::PixelFormat::kYuyv);
    ASSERT_TRUE(parse_capture_format("uyvy", f));
    EXPECT_EQ(info(f).fourcc, V4L2_PIX_FMT_UYVY);
    EXPECT_EQ(info(f).pixel, hal::PixelFormat::kUyvy);
    ASSERT_TRUE(parse_capture_format("nv12", f));
    EXPECT_EQ(info(f).fourcc, V4L2_PIX_FMT_NV12);
    EXPECT_EQ(info(f).pixel, hal::PixelFormat::kNv12);
    ASSERT_TRUE(parse_capture_format("bgrx", f));
    EXPECT_EQ(info(f).fourcc, V4L2_PIX_FMT_XBGR32);
    EXPECT_EQ(info(f).pixel, hal::PixelFormat::kBgra32);
    ASSERT_TRUE(parse_capture_format("mjpeg", f));
    EXPECT_EQ(info(f).fourcc, V4L2_PIX_FMT_MJPEG);
    EXPECT_EQ(info(f).pixel, hal::PixelFormat::kBgr24);  // decoded by MjpegDecoder
    EXPECT_TRUE(info(f).supported);
    EXPECT_FALSE(parse_capture_format("YUYV", f));
    EXPECT_FALSE(parse_capture_format("rgb24", f));
    ASSERT_NE(find_fourcc(V4L2_PIX_FMT_NV12), nullptr);
    EXPECT_EQ(find_fourcc(V4L2_PIX_FMT_NV12)->name, "nv12");
    EXPECT_EQ(find_fourcc(V4L2_PIX_FMT_RGB24), nullptr);
    EXPECT_EQ(fourcc_name(V4L2_PIX_FMT_YUYV), "YUYV");
    EXPECT_EQ(fourcc_name(V4L2_PIX_FMT_MJPEG), "MJPG");
    EXPECT_EQ(fourcc_name(0x01020304), "????");
}

TEST(CaptureFormat, DvTimingsNames) {
    DvTimingsName d;
    ASSERT_TRUE(parse_dv_timings_name("1920x1080p60", d));
    EXPECT_EQ(d.width, 1920);
    EXPECT_EQ(d.height, 1080);
    EXPECT_FALSE(d.interlaced);
    EXPECT_DOUBLE_EQ(d.hz, 60.0);
    ASSERT_TRUE(parse_dv_timings_name("1920x1080i50", d));
    EXPECT_TRUE(d.interlaced);
    ASSERT_TRUE(parse_dv_timings_name("1280x720p59.94", d));
    EXPECT_DOUBLE_EQ(d.hz, 59.94);
    for (const char* bad :
         {"", "1920x1080", "1920x1080p", "1920*1080p60", "x1080p60", "1920x1080p60Hz", "0x1080p60",
          "1920x1080q60", "1920x1080p0", "99999x1080p60"})
        EXPECT_FALSE(parse_dv_timings_name(bad, d)) << bad;
}

TEST(CaptureFormat, DvRefreshAndMatching) {
    // CEA-861 1080p60: 148.5 MHz over 2200 x 1125 = 60 Hz exactly; 1080p59.94 is /1.001.
    EXPECT_DOUBLE_EQ(dv_refresh_hz(148'500'000, 2200, 1125), 60.0);
    EXPECT_NEAR(dv_refresh_hz(148'351'648, 2200, 1125), 59.94, 0.001);
    EXPECT_EQ(dv_refresh_hz(148'500'000, 0, 1125), 0.0);
    DvTimingsName want;
    ASSERT_TRUE(parse_dv_timings_name("1920x1080p60", want));
    EXPECT_TRUE(dv_matches(want, 1920, 1080, false, 60.0));
    EXPECT_TRUE(dv_matches(want, 1920, 1080, false, 59.94));  // within 0.5 %
    EXPECT_FALSE(dv_matches(want, 1920, 1080, false, 50.0));
    EXPECT_FALSE(dv_matches(want, 1920, 1080, true, 60.0));
    EXPECT_FALSE(dv_matches(want, 1280, 720, false, 60.0));
}

}  // namespace
}  // namespace endotower::v4l2
