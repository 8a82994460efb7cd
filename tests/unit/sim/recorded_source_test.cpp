#include "endotower/sim/recorded_source.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <thread>
#include <vector>

#include "endotower/sim/virtual_clock.hpp"
#include "endotower/system/monotonic_clock.hpp"
#include "test_util.hpp"

namespace endotower::sim {
namespace {

using hal::Frame;
using hal::SourceStatus;
namespace fs = std::filesystem;

constexpr hal::Nanos kT0 = 1'000'000;
constexpr hal::Nanos k25Fps = 40'000'000;

// Frame k's picture: every pixel differs between frames and within a frame.
cv::Mat picture(int k, int width = 32, int height = 24) {
    cv::Mat m(height, width, CV_8UC3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            m.at<cv::Vec3b>(y, x) =
                cv::Vec3b(static_cast<uchar>(k * 40 + x), static_cast<uchar>(k * 7 + y),
                          static_cast<uchar>(x * y + k));
    return m;
}

bool same_pixels(const Frame& f, const cv::Mat& expected) {
    if (f.format.width != expected.cols || f.format.height != expected.rows) return false;
    const cv::Mat got(f.format.height, f.format.width, CV_8UC3, f.data,
                      static_cast<std::size_t>(f.format.stride));
    return cv::norm(got, expected, cv::NORM_INF) == 0;
}

TEST(RecordedSource, ImageDirectoryInNumericOrderPacedOnTheClock) {
    test::TempDir dir("frames");
    // Name order would be 1, 10, 11, 2.
    const int numbers[] = {1, 2, 10, 11};
    for (int i = 0; i < 4; ++i)
        ASSERT_TRUE(
            cv::imwrite(dir.file("img_" + std::to_string(numbers[i]) + ".png"), picture(i)));
    std::ofstream(dir.file("notes.txt")) << "not an image";
    ASSERT_TRUE(cv::imwrite(dir.file(".hidden_0.png"), picture(9)));

    VirtualClock clock(kT0);
    RecordedFrameSource src({dir.path().string(), 0.0, 3}, clock);
    ASSERT_TRUE(src.open()) << src.error();
    EXPECT_EQ(src.expected_frames(), 4);
    ASSERT_TRUE(src.start()) << src.error();
    EXPECT_EQ(src.frame_period(), k25Fps);
    EXPECT_EQ(src.buffer_count(), 3);
    const hal::FrameFormat fmt = src.format();
    EXPECT_EQ(fmt.width, 32);
    EXPECT_EQ(fmt.height, 24);
    EXPECT_EQ(fmt.stride, 96);
    EXPECT_EQ(fmt.pixel_format, hal::PixelFormat::kBgr24);

    for (int i = 0; i < 4; ++i) {
        Frame f;
        ASSERT_EQ(src.next(f, hal::kSecond), SourceStatus::kFrame) << i << ": " << src.error();
        EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(i));
        EXPECT_EQ(f.capture_ns, kT0 + i * k25Fps);
        EXPECT_EQ(clock.now(), kT0 + i * k25Fps);  // the virtual clock jumped to it
        EXPECT_EQ(f.format, fmt);
        EXPECT_GE(f.buffer_index, 0);
        EXPECT_LT(f.buffer_index, 3);
        EXPECT_TRUE(same_pixels(f, picture(i))) << "frame " << i;
        src.release(f);
    }
    Frame f;
    EXPECT_EQ(src.next(f, hal::kSecond), SourceStatus::kEndOfStream);
    EXPECT_EQ(src.next(f, hal::kSecond), SourceStatus::kEndOfStream);
    EXPECT_EQ(src.frames_read(), 4);
    EXPECT_EQ(src.skipped_frames(), 0);
    EXPECT_FALSE(src.truncated());
    EXPECT_EQ(src.warning(), "");
}

TEST(RecordedSource, LateVirtualClockKeepsScheduledTimestamps) {
    test::TempDir dir("frames");
    for (int i = 0; i < 3; ++i)
        ASSERT_TRUE(cv::imwrite(dir.file(std::to_string(i) + ".png"), picture(i)));
    VirtualClock clock(0);
    RecordedFrameSource src({dir.path().string(), 50.0, 6}, clock);  // fps override: 20 ms
    ASSERT_TRUE(src.start()) << src.error();  // start() opens when open() was not called
    EXPECT_EQ(src.frame_period(), 20'000'000);
    clock.sleep_until(hal::kSecond);  // the pipeline fell behind
    for (int i = 0; i < 3; ++i) {
        Frame f;
        ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame);
        EXPECT_EQ(f.capture_ns, i * 20'000'000);
        EXPECT_EQ(clock.now(), hal::kSecond);  // no sleep backwards
        src.release(f);
    }
}

TEST(RecordedSource, FormatChangeThenTheNewFrame) {
    test::TempDir dir("frames");
    ASSERT_TRUE(cv::imwrite(dir.file("0.png"), picture(0)));
    ASSERT_TRUE(cv::imwrite(dir.file("1.png"), picture(1)));
    ASSERT_TRUE(cv::imwrite(dir.file("2.png"), picture(2, 16, 12)));
    ASSERT_TRUE(cv::imwrite(dir.file("3.png"), picture(3, 16, 12)));
    VirtualClock clock(kT0);
    RecordedFrameSource src({dir.path().string(), 0.0, 2}, clock);
    ASSERT_TRUE(src.start()) << src.error();
    Frame f;
    for (int i = 0; i < 2; ++i) {
        ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame);
        EXPECT_TRUE(same_pixels(f, picture(i)));
        src.release(f);
    }
    ASSERT_EQ(src.next(f, 0), SourceStatus::kFormatChange);
    EXPECT_EQ(src.format(), (hal::FrameFormat{16, 12, 48, hal::PixelFormat::kBgr24}));
    for (int i = 2; i < 4; ++i) {
        ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame);
        EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(i));
        EXPECT_EQ(f.capture_ns, kT0 + i * k25Fps);
        EXPECT_EQ(f.format, src.format());
        EXPECT_TRUE(same_pixels(f, picture(i, 16, 12)));
        src.release(f);
    }
    EXPECT_EQ(src.next(f, 0), SourceStatus::kEndOfStream);
}

TEST(RecordedSource, CorruptImageIsSkippedAndCounted) {
    test::TempDir dir("frames");
    ASSERT_TRUE(cv::imwrite(dir.file("0.png"), picture(0)));
    ASSERT_TRUE(cv::imwrite(dir.file("1.png"), picture(1)));
    std::ofstream(dir.file("2.png")) << "\x89PNG but then nothing useful";
    ASSERT_TRUE(cv::imwrite(dir.file("3.png"), picture(3)));
    VirtualClock clock(kT0);
    RecordedFrameSource src({dir.path().string(), 0.0, 6}, clock);
    ASSERT_TRUE(src.start()) << src.error();
    const int expected_seq[] = {0, 1, 3};
    for (int seq : expected_seq) {
        Frame f;
        ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame);
        EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(seq));  // the gap shows the drop
        EXPECT_EQ(f.capture_ns, kT0 + seq * k25Fps);
        EXPECT_TRUE(same_pixels(f, picture(seq)));
        src.release(f);
    }
    Frame f;
    EXPECT_EQ(src.next(f, 0), SourceStatus::kEndOfStream);
    EXPECT_EQ(src.skipped_frames(), 1);
    EXPECT_EQ(src.frames_read(), 3);
    EXPECT_FALSE(src.truncated());
    EXPECT_EQ(src.warning(), "skipped 1 unreadable image(s) in " + dir.path().string() +
                                 " (first: " + dir.file("2.png") + ")");
}

TEST(RecordedSource, GrayAlphaAnd16BitImagesBecomeBgr24) {
    test::TempDir dir("frames");
    cv::Mat gray(4, 6, CV_8UC1, cv::Scalar(77));
    cv::Mat bgra(4, 6, CV_8UC4, cv::Scalar(10, 20, 30, 128));
    cv::Mat deep(4, 6, CV_16UC3, cv::Scalar(50 * 257, 100 * 257, 200 * 257));
    ASSERT_TRUE(cv::imwrite(dir.file("0.png"), gray));
    ASSERT_TRUE(cv::imwrite(dir.file("1.png"), bgra));
    ASSERT_TRUE(cv::imwrite(dir.file("2.png"), deep));
    ASSERT_TRUE(cv::imwrite(dir.file("3.bmp"), picture(3, 6, 4)));
    VirtualClock clock;
    RecordedFrameSource src({dir.path().string(), 0.0, 6}, clock);
    ASSERT_TRUE(src.start()) << src.error();
    const cv::Mat expected[] = {cv::Mat(4, 6, CV_8UC3, cv::Scalar(77, 77, 77)),
                                cv::Mat(4, 6, CV_8UC3, cv::Scalar(10, 20, 30)),
                                cv::Mat(4, 6, CV_8UC3, cv::Scalar(50, 100, 200)), picture(3, 6, 4)};
    for (int i = 0; i < 4; ++i) {
        Frame f;
        ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame) << i;
        EXPECT_EQ(f.format.pixel_format, hal::PixelFormat::kBgr24);
        EXPECT_TRUE(same_pixels(f, expected[i])) << i;
        src.release(f);
    }
}

TEST(RecordedSource, PoolExhaustionTimesOutAndReleaseFromAnotherThreadFrees) {
    test::TempDir dir("frames");
    for (int i = 0; i < 4; ++i)
        ASSERT_TRUE(cv::imwrite(dir.file(std::to_string(i) + ".png"), picture(i)));
    VirtualClock clock;
    RecordedFrameSource src({dir.path().string(), 0.0, 2}, clock);
    ASSERT_TRUE(src.start());
    Frame a, b, c;
    ASSERT_EQ(src.next(a, 0), SourceStatus::kFrame);
    ASSERT_EQ(src.next(b, 0), SourceStatus::kFrame);
    EXPECT_NE(a.buffer_index, b.buffer_index);
    EXPECT_NE(a.data, b.data);
    EXPECT_EQ(src.next(c, 0), SourceStatus::kTimeout);
    EXPECT_EQ(src.next(c, 5 * hal::kMillisecond), SourceStatus::kTimeout);

    // Frame 2 waits for a buffer; another thread gives one back.
    std::thread releaser([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        src.release(a);
    });
    const auto t = std::chrono::steady_clock::now();
    ASSERT_EQ(src.next(c, 10 * hal::kSecond), SourceStatus::kFrame);
    EXPECT_LT(std::chrono::steady_clock::now() - t, std::chrono::seconds(5));
    releaser.join();
    EXPECT_EQ(c.buffer_index, a.buffer_index);
    EXPECT_EQ(c.sequence, 2u);
    EXPECT_TRUE(same_pixels(c, picture(2)));
    EXPECT_TRUE(same_pixels(b, picture(1)));  // the lent buffer was not touched
    src.release(a);                           // a double release is ignored
    src.release(b);
    src.release(c);
    ASSERT_EQ(src.next(c, 0), SourceStatus::kFrame);
    EXPECT_EQ(c.sequence, 3u);
}

TEST(RecordedSource, RealClockPacesFramesAndHonoursTheTimeout) {
    test::TempDir dir("frames");
    for (int i = 0; i < 3; ++i)
        ASSERT_TRUE(cv::imwrite(dir.file(std::to_string(i) + ".png"), picture(i)));
    system::MonotonicClock clock;
    RecordedFrameSource src({dir.path().string(), 5.0, 6}, clock);  // 200 ms per frame
    ASSERT_TRUE(src.start());
    Frame f0, f1;
    ASSERT_EQ(src.next(f0, hal::kSecond), SourceStatus::kFrame);
    // Frame 1 is due 200 ms after frame 0: a 10 ms timeout expires first.
    EXPECT_EQ(src.next(f1, 10 * hal::kMillisecond), SourceStatus::kTimeout);
    ASSERT_EQ(src.next(f1, hal::kSecond), SourceStatus::kFrame);
    EXPECT_EQ(f1.capture_ns - f0.capture_ns, 200 * hal::kMillisecond);
    EXPECT_GE(clock.now(), f1.capture_ns);
    EXPECT_EQ(f1.sequence, 1u);
    EXPECT_TRUE(same_pixels(f1, picture(1)));
}

TEST(RecordedSource, StopThenStartReplaysFromTheBeginning) {
    test::TempDir dir("frames");
    for (int i = 0; i < 2; ++i)
        ASSERT_TRUE(cv::imwrite(dir.file(std::to_string(i) + ".png"), picture(i)));
    VirtualClock clock;
    RecordedFrameSource src({dir.path().string(), 0.0, 6}, clock);
    Frame f;
    EXPECT_EQ(src.next(f, 0), SourceStatus::kError);  // not started
    ASSERT_TRUE(src.start());
    ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame);
    src.release(f);
    src.stop();
    ASSERT_TRUE(src.start());
    ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame);
    EXPECT_EQ(f.sequence, 0u);
    EXPECT_TRUE(same_pixels(f, picture(0)));
}

TEST(RecordedSource, OpenErrorsNameThePath) {
    test::TempDir dir("errors");
    VirtualClock clock;
    const std::string missing = dir.file("nope.mp4");
    RecordedFrameSource a({missing}, clock);
    EXPECT_FALSE(a.open());
    EXPECT_EQ(a.error(), "recording not found: " + missing);
    EXPECT_FALSE(a.start());

    fs::create_directories(dir.path() / "empty");
    std::ofstream(dir.file("empty/readme.txt")) << "no images here";
    const std::string empty = dir.file("empty");
    RecordedFrameSource b({empty}, clock);
    EXPECT_FALSE(b.open());
    EXPECT_EQ(b.error(), "no images (png/jpg/bmp/tif) in directory: " + empty);

    const std::string text = dir.file("clip.mp4");
    std::ofstream(text) << "this is not a video at all\n";
    RecordedFrameSource c({text}, clock);
    EXPECT_FALSE(c.open());
    EXPECT_EQ(c.error(), "cannot decode video: " + text + " (unsupported codec or not a video)");

    const std::string zero = dir.file("zero.mkv");
    std::ofstream(zero).close();  // an empty file
    RecordedFrameSource d({zero}, clock);
    EXPECT_FALSE(d.open());
    EXPECT_EQ(d.error(), "cannot decode video: " + zero + " (unsupported codec or not a video)");

    fs::create_directories(dir.path() / "broken");
    std::ofstream(dir.file("broken/0.png")) << "garbage";
    std::ofstream(dir.file("broken/1.jpg")) << "garbage";
    RecordedFrameSource e({dir.file("broken")}, clock);
    EXPECT_FALSE(e.open());
    EXPECT_EQ(e.error(), "no readable image in directory: " + dir.file("broken") +
                             " (2 files, none could be decoded)");
}

// A lossless FFV1 clip written with OpenCV; returns the frames written.
std::vector<cv::Mat> write_clip(const std::string& path, int frames, int w, int h, double fps,
                                bool noise) {
    cv::VideoWriter writer(path, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'), fps,
                           cv::Size(w, h), true);
    EXPECT_TRUE(writer.isOpened());
    std::vector<cv::Mat> out;
    cv::RNG rng(42);
    for (int i = 0; i < frames; ++i) {
        cv::Mat m = picture(i, w, h);
        if (noise) rng.fill(m, cv::RNG::UNIFORM, 0, 256);
        writer.write(m);
        out.push_back(m);
    }
    return out;
}

TEST(RecordedSource, LosslessVideoFileExactPixels) {
    test::TempDir dir("video");
    const std::string path = dir.file("clip.mkv");
    const auto frames = write_clip(path, 10, 64, 48, 30.0, false);
    VirtualClock clock(kT0);
    RecordedFrameSource src({path, 0.0, 4}, clock);
    ASSERT_TRUE(src.open()) << src.error();
    EXPECT_EQ(src.expected_frames(), 10);
    EXPECT_EQ(src.frame_period(), 33'333'333);
    EXPECT_EQ(src.format(), (hal::FrameFormat{64, 48, 192, hal::PixelFormat::kBgr24}));
    ASSERT_TRUE(src.start());
    for (int i = 0; i < 10; ++i) {
        Frame f;
        ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame) << i;
        EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(i));
        EXPECT_EQ(f.capture_ns, kT0 + std::llround(i * 1e9 / 30.0));
        EXPECT_TRUE(same_pixels(f, frames[i])) << "frame " << i;
        src.release(f);
    }
    Frame f;
    EXPECT_EQ(src.next(f, 0), SourceStatus::kEndOfStream);
    EXPECT_FALSE(src.truncated());
    EXPECT_EQ(src.warning(), "");
    EXPECT_EQ(src.frames_read(), 10);
}

// loops (toolchain/soak.sh): the file again from its first frame, the index, capture
// time and sequence running on.
TEST(RecordedSource, LoopsReplayTheFileWithTimeRunningOn) {
    test::TempDir dir("video");
    const std::string path = dir.file("clip.mkv");
    const auto frames = write_clip(path, 10, 64, 48, 30.0, false);
    VirtualClock clock(kT0);
    RecordedFrameSource src({path, 0.0, 4, 3}, clock);
    ASSERT_TRUE(src.open()) << src.error();
    ASSERT_TRUE(src.start());
    for (int i = 0; i < 30; ++i) {
        Frame f;
        ASSERT_EQ(src.next(f, 0), SourceStatus::kFrame) << i;
        EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(i));
        EXPECT_EQ(f.capture_ns, kT0 + std::llround(i * 1e9 / 30.0));
        EXPECT_TRUE(same_pixels(f, frames[static_cast<std::size_t>(i % 10)])) << "frame " << i;
        src.release(f);
    }
    Frame f;
    EXPECT_EQ(src.next(f, 0), SourceStatus::kEndOfStream);
    EXPECT_EQ(src.frames_read(), 30);
}

TEST(RecordedSource, TruncatedVideoEndsAtTheLastGoodFrame) {
    test::TempDir dir("video");
    const std::string path = dir.file("cut.mkv");
    const auto frames = write_clip(path, 30, 160, 120, 25.0, true);
    fs::resize_file(path, fs::file_size(path) / 2);
    VirtualClock clock;
    RecordedFrameSource src({path, 0.0, 6}, clock);
    ASSERT_TRUE(src.open()) << src.error();
    EXPECT_EQ(src.expected_frames(), 30);
    ASSERT_TRUE(src.start());
    int n = 0;
    SourceStatus s;
    Frame f;
    while ((s = src.next(f, 0)) == SourceStatus::kFrame) {
        EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(n));
        EXPECT_TRUE(same_pixels(f, frames[n])) << "frame " << n;
        src.release(f);
        ++n;
    }
    EXPECT_EQ(s, SourceStatus::kEndOfStream);
    EXPECT_GT(n, 0);
    EXPECT_LT(n, 30);
    EXPECT_EQ(src.frames_read(), n);
    EXPECT_TRUE(src.truncated());
    EXPECT_EQ(src.warning(), "recording " + path + " ends after " + std::to_string(n) +
                                 " of 30 frames (truncated or corrupt)");
}

TEST(RecordedSource, RealLaparoscopyClip) {
    const std::string path = std::string(ENDOTOWER_SHARED_DATA) + "/sznitman_lap/frames";
    if (!fs::is_directory(path)) GTEST_SKIP() << "../shared/data/sznitman_lap absent";
    VirtualClock clock;
    RecordedFrameSource src({path, 0.0, 6}, clock);
    ASSERT_TRUE(src.open()) << src.error();
    EXPECT_EQ(src.expected_frames(), 400);
    EXPECT_EQ(src.format(), (hal::FrameFormat{384, 288, 384 * 3, hal::PixelFormat::kBgr24}));
    ASSERT_TRUE(src.start());
    const cv::Mat first = cv::imread(path + "/001175.png", cv::IMREAD_COLOR);
    const cv::Mat last = cv::imread(path + "/001574.png", cv::IMREAD_COLOR);
    int n = 0;
    Frame f;
    SourceStatus s;
    while ((s = src.next(f, 0)) == SourceStatus::kFrame) {
        EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(n));
        EXPECT_EQ(f.capture_ns, n * k25Fps);
        if (n == 0) {
            EXPECT_TRUE(same_pixels(f, first));
        } else if (n == 399) {
            EXPECT_TRUE(same_pixels(f, last));
        }
        src.release(f);
        ++n;
    }
    EXPECT_EQ(s, SourceStatus::kEndOfStream);
    EXPECT_EQ(n, 400);
    EXPECT_EQ(src.skipped_frames(), 0);
}

}  // namespace
}  // namespace endotower::sim
