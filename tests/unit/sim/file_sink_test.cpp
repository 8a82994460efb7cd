#include "endotower/sim/file_sink.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "endotower/sim/compositor.hpp"
#include "endotower/sim/virtual_clock.hpp"
#include "test_util.hpp"

namespace endotower::sim {
namespace {

using hal::Frame;
using hal::FrameFormat;
using hal::PixelFormat;
namespace fs = std::filesystem;

constexpr hal::Nanos kPeriod = 40 * hal::kMillisecond;

// A BGR24 video frame with content that changes per frame, and an overlay with a
// rectangle of opaque, transparent and half-transparent pixels.
struct Scene {
    cv::Mat video;
    std::vector<std::uint8_t> rgba;
    hal::OverlayLayer overlay;

    Scene(int k, int w, int h) : video(h, w, CV_8UC3), rgba(static_cast<std::size_t>(w) * h * 4) {
        cv::RNG rng(static_cast<std::uint64_t>(k) + 1);
        rng.fill(video, cv::RNG::UNIFORM, 0, 256);
        overlay.width = w;
        overlay.height = h;
        overlay.stride = w * 4;
        overlay.rgba = rgba.data();
        for (std::size_t i = 0; i < rgba.size(); i += 4) {
            rgba[i] = static_cast<std::uint8_t>(i + k);
            rgba[i + 1] = 200;
            rgba[i + 2] = static_cast<std::uint8_t>(k * 30);
            rgba[i + 3] = static_cast<std::uint8_t>((i / 4) % 3 == 0   ? 0
                                                    : (i / 4) % 3 == 1 ? 255
                                                                       : 100);
        }
        overlay.rects[0] = hal::Rect{w / 4, h / 4, w / 2, h / 2};
        overlay.rect_count = 1;
    }
    Frame frame() const {
        Frame f;
        f.format =
            FrameFormat{video.cols, video.rows, static_cast<int>(video.step), PixelFormat::kBgr24};
        f.data = video.data;
        return f;
    }
    cv::Mat composed() const {
        cv::Mat out(video.rows, video.cols, CV_8UC3);
        EXPECT_TRUE(compose(frame(), &overlay, out.data, static_cast<int>(out.step)));
        return out;
    }
};

std::vector<cv::Mat> read_video(const std::string& path) {
    std::vector<cv::Mat> frames;
    cv::VideoCapture cap(path, cv::CAP_FFMPEG);
    cv::Mat m;
    while (cap.isOpened() && cap.read(m)) frames.push_back(m.clone());
    return frames;
}

bool equal(const cv::Mat& a, const cv::Mat& b) {
    return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

bool no_hidden_files(const test::TempDir& dir, const std::string& sub = "") {
    for (const auto& e : fs::recursive_directory_iterator(dir.path() / sub))
        if (e.path().filename().string().starts_with('.')) return false;
    return true;
}

TEST(FileSink, WritesComposedPngsAndALosslessVideo) {
    test::TempDir dir("sink");
    VirtualClock clock(0);
    FileSink sink({dir.file("out.mkv"), dir.file("frames"), 25.0}, clock);
    const int kFrames = 5;
    std::vector<cv::Mat> expected;
    ASSERT_TRUE(sink.configure(Scene(0, 64, 48).frame().format)) << sink.error();
    for (int i = 0; i < kFrames; ++i) {
        const Scene s(i, 64, 48);
        expected.push_back(s.composed());
        const hal::Nanos due = 1000 + i * kPeriod;
        EXPECT_EQ(sink.present(s.frame(), &s.overlay, due), due) << sink.error();
        EXPECT_EQ(clock.now(), due);
    }
    EXPECT_EQ(sink.frames_written(), kFrames);
    // Nothing under the final video name until finish().
    EXPECT_FALSE(fs::exists(dir.file("out.mkv")));
    ASSERT_TRUE(sink.finish()) << sink.error();

    EXPECT_EQ(dir.list(), (std::vector<std::string>{"frames", "out.mkv"}));
    EXPECT_TRUE(no_hidden_files(dir));
    for (int i = 0; i < kFrames; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "frames/%06d.png", i);
        const cv::Mat png = cv::imread(dir.file(name), cv::IMREAD_UNCHANGED);
        EXPECT_TRUE(equal(png, expected[i])) << name;
    }
    EXPECT_FALSE(fs::exists(dir.file("frames/000005.png")));
    const auto video = read_video(dir.file("out.mkv"));
    ASSERT_EQ(video.size(), static_cast<std::size_t>(kFrames));
    for (int i = 0; i < kFrames; ++i) EXPECT_TRUE(equal(video[i], expected[i])) << "frame " << i;
    cv::VideoCapture cap(dir.file("out.mkv"), cv::CAP_FFMPEG);
    EXPECT_EQ(cap.get(cv::CAP_PROP_FPS), 25.0);
}

TEST(FileSink, PresentReturnsTheLaterOfDueAndNow) {
    test::TempDir dir("sink");
    VirtualClock clock(hal::kSecond);
    FileSink sink({"", dir.file("frames"), 25.0}, clock);
    const Scene s(0, 16, 8);
    ASSERT_TRUE(sink.configure(s.frame().format));
    EXPECT_EQ(sink.present(s.frame(), nullptr, hal::kSecond / 2), hal::kSecond);  // late
    EXPECT_EQ(clock.now(), hal::kSecond);
    EXPECT_EQ(sink.present(s.frame(), nullptr, 3 * hal::kSecond), 3 * hal::kSecond);
    EXPECT_EQ(clock.now(), 3 * hal::kSecond);
    ASSERT_TRUE(sink.finish());
    // No overlay: the PNG is the video, bit for bit.
    EXPECT_TRUE(equal(cv::imread(dir.file("frames/000000.png"), cv::IMREAD_UNCHANGED), s.video));
}

TEST(FileSink, FormatChangeStartsANewSegment) {
    test::TempDir dir("sink");
    VirtualClock clock;
    FileSink sink({dir.file("out.mkv"), "", 25.0}, clock);
    const Scene big(1, 64, 48), small(2, 32, 24);
    ASSERT_TRUE(sink.configure(big.frame().format));
    for (int i = 0; i < 3; ++i) ASSERT_GE(sink.present(big.frame(), &big.overlay, i * kPeriod), 0);
    ASSERT_TRUE(sink.configure(big.frame().format));  // the same format: same segment
    ASSERT_GE(sink.present(big.frame(), &big.overlay, 3 * kPeriod), 0);
    ASSERT_TRUE(sink.configure(small.frame().format)) << sink.error();
    EXPECT_TRUE(fs::exists(dir.file("out.mkv")));  // the first segment is complete
    for (int i = 0; i < 2; ++i)
        ASSERT_GE(sink.present(small.frame(), &small.overlay, (4 + i) * kPeriod), 0);
    ASSERT_TRUE(sink.finish()) << sink.error();
    EXPECT_EQ(sink.frames_written(), 6);
    EXPECT_EQ(dir.list(), (std::vector<std::string>{"out.1.mkv", "out.mkv"}));

    const auto first = read_video(dir.file("out.mkv"));
    ASSERT_EQ(first.size(), 4u);
    EXPECT_TRUE(equal(first[3], big.composed()));
    const auto second = read_video(dir.file("out.1.mkv"));
    ASSERT_EQ(second.size(), 2u);
    EXPECT_TRUE(equal(second[0], small.composed()));
}

TEST(FileSink, DestructorWithoutFinishStillNamesTheVideo) {
    test::TempDir dir("sink");
    VirtualClock clock;
    {
        FileSink sink({dir.file("clip.avi"), "", 25.0}, clock);
        const Scene s(0, 32, 16);
        ASSERT_TRUE(sink.configure(s.frame().format));
        ASSERT_GE(sink.present(s.frame(), nullptr, 0), 0) << sink.error();
        ASSERT_GE(sink.present(s.frame(), nullptr, kPeriod), 0);
    }
    EXPECT_EQ(dir.list(), (std::vector<std::string>{"clip.avi"}));
    EXPECT_EQ(read_video(dir.file("clip.avi")).size(), 2u);  // MJPG: lossy, count only
}

TEST(FileSink, YuyvInputIsConvertedThenBlended) {
    test::TempDir dir("sink");
    VirtualClock clock;
    FileSink sink({"", dir.file("frames"), 25.0}, clock);
    cv::Mat yuyv(8, 16, CV_8UC2);
    cv::RNG(7).fill(yuyv, cv::RNG::UNIFORM, 0, 256);
    Frame f;
    f.format = FrameFormat{16, 8, 32, PixelFormat::kYuyv};
    f.data = yuyv.data;
    std::vector<std::uint8_t> rgba(16 * 8 * 4, 0);
    hal::OverlayLayer ov;
    ov.width = 16, ov.height = 8, ov.stride = 64, ov.rgba = rgba.data();
    ov.rects[0] = hal::Rect{0, 0, 2, 1};
    ov.rect_count = 1;
    rgba[0] = 255, rgba[1] = 0, rgba[2] = 0, rgba[3] = 255;  // opaque red at (0,0)
    ASSERT_TRUE(sink.configure(f.format));
    ASSERT_GE(sink.present(f, &ov, 0), 0) << sink.error();
    cv::Mat expected;
    cv::cvtColor(yuyv, expected, cv::COLOR_YUV2BGR_YUYV);
    expected.at<cv::Vec3b>(0, 0) = cv::Vec3b(0, 0, 255);
    EXPECT_TRUE(equal(cv::imread(dir.file("frames/000000.png"), cv::IMREAD_UNCHANGED), expected));
}

TEST(FileSink, PaddedNv12AndBgra32InputsAreConverted) {
    test::TempDir dir("sink");
    VirtualClock clock;
    // NV12 16x8 with 8 bytes of row padding: Y plane, then interleaved UV, same stride.
    const int stride = 24;
    std::vector<std::uint8_t> nv12(static_cast<std::size_t>(stride) * 12);
    cv::Mat packed(12, 16, CV_8UC1);
    cv::RNG(3).fill(packed, cv::RNG::UNIFORM, 0, 256);
    for (int y = 0; y < 12; ++y)
        std::memcpy(&nv12[static_cast<std::size_t>(y) * stride], packed.ptr(y), 16);
    Frame f;
    f.format = FrameFormat{16, 8, stride, PixelFormat::kNv12};
    f.data = nv12.data();
    FileSink sink({"", dir.file("nv12"), 25.0}, clock);
    ASSERT_TRUE(sink.configure(f.format)) << sink.error();
    ASSERT_GE(sink.present(f, nullptr, 0), 0) << sink.error();
    cv::Mat expected;
    cv::cvtColor(packed, expected, cv::COLOR_YUV2BGR_NV12);
    EXPECT_TRUE(equal(cv::imread(dir.file("nv12/000000.png"), cv::IMREAD_UNCHANGED), expected));

    cv::Mat bgra(8, 16, CV_8UC4);
    cv::RNG(4).fill(bgra, cv::RNG::UNIFORM, 0, 256);
    f.format = FrameFormat{16, 8, 64, PixelFormat::kBgra32};
    f.data = bgra.data;
    FileSink sink2({"", dir.file("bgra"), 25.0}, clock);
    ASSERT_TRUE(sink2.configure(f.format));
    ASSERT_GE(sink2.present(f, nullptr, 0), 0) << sink2.error();
    cv::cvtColor(bgra, expected, cv::COLOR_BGRA2BGR);
    EXPECT_TRUE(equal(cv::imread(dir.file("bgra/000000.png"), cv::IMREAD_UNCHANGED), expected));
}

TEST(FileSink, Errors) {
    test::TempDir dir("sink");
    VirtualClock clock;
    const Scene s(0, 16, 8);

    FileSink bad_ext({dir.file("out.xyz"), "", 25.0}, clock);
    EXPECT_FALSE(bad_ext.configure(s.frame().format));
    EXPECT_EQ(bad_ext.error(), "cannot write video " + dir.file("out.xyz") +
                                   ": unsupported extension '.xyz' (use .mkv, .avi or .mp4)");

    std::ofstream(dir.file("plain")) << "a file, not a directory";
    const std::string frames = dir.file("plain/frames");
    FileSink bad_dir({"", frames, 25.0}, clock);
    EXPECT_FALSE(bad_dir.configure(s.frame().format));
    EXPECT_EQ(bad_dir.error(), "cannot create frames directory " + frames + ": Not a directory");

    FileSink sink({"", dir.file("frames"), 25.0}, clock);
    EXPECT_LT(sink.present(s.frame(), nullptr, 0), 0);
    EXPECT_EQ(sink.error(), "file sink: present() before configure()");
    EXPECT_FALSE(sink.configure(FrameFormat{0, 8, 0, PixelFormat::kBgr24}));
    EXPECT_EQ(sink.error(), "file sink: invalid video format 0x8 bgr24");
    ASSERT_TRUE(sink.configure(s.frame().format));
    const Scene other(0, 8, 8);
    EXPECT_LT(sink.present(other.frame(), nullptr, 0), 0);
    EXPECT_EQ(sink.error(), "file sink: frame 8x8 bgr24 does not match the configured 16x8 bgr24");
    hal::OverlayLayer wrong = s.overlay;
    wrong.width = 15;
    EXPECT_LT(sink.present(s.frame(), &wrong, 0), 0);
    EXPECT_EQ(sink.error(), "file sink: overlay does not match the 16x8 bgr24 video");
    EXPECT_EQ(sink.frames_written(), 0);

    // The video's directory disappears before the first frame.
    fs::create_directories(dir.path() / "videos");
    FileSink gone({dir.file("videos/out.mkv"), "", 25.0}, clock);
    ASSERT_TRUE(gone.configure(s.frame().format)) << gone.error();
    fs::remove_all(dir.path() / "videos");
    EXPECT_LT(gone.present(s.frame(), nullptr, 0), 0);
    EXPECT_EQ(gone.error(), "cannot write video " + dir.file("videos/out.mkv") + ": access(" +
                                dir.file("videos") + "): No such file or directory (errno 2)");
    EXPECT_TRUE(gone.finish());  // nothing was written, nothing to name

    // The frames directory disappears under the sink: the message names the file
    // and the errno text.
    fs::remove_all(dir.file("frames"));
    EXPECT_LT(sink.present(s.frame(), nullptr, 0), 0);
    EXPECT_EQ(sink.error(), "cannot write frame: write(" + dir.file("frames/.000000.tmp.png") +
                                "): No such file or directory (errno 2)");
}

}  // namespace
}  // namespace endotower::sim
