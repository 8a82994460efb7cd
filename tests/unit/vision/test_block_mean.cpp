// BlockMean and AreaMean: the integer-factor and the general reduction give cv::resize's
// INTER_AREA bytes.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "endotower/vision/area_mean.hpp"
#include "endotower/vision/block_mean.hpp"

using endotower::vision::AreaMean;
using endotower::vision::BlockMean;

namespace {

// Random bytes with a few saturated patches (sums near 255 k^2 and 0).
cv::Mat noise(int w, int h, int channels, int seed) {
    cv::Mat m(h, w, CV_8UC(channels));
    cv::RNG rng(static_cast<std::uint64_t>(seed));
    rng.fill(m, cv::RNG::UNIFORM, 0, 256);
    m(cv::Rect(0, 0, w / 4, h / 4)).setTo(cv::Scalar::all(255));
    m(cv::Rect(w / 2, h / 2, w / 4, h / 4)).setTo(cv::Scalar::all(0));
    return m;
}

void expect_like_inter_area(int w, int h, int k, int channels) {
    const cv::Mat src = noise(w, h, channels, w + k);
    cv::Mat want, got(h / k, w / k, CV_8UC(channels), cv::Scalar::all(7));
    cv::resize(src, want, got.size(), 0, 0, cv::INTER_AREA);
    BlockMean reduce;
    ASSERT_TRUE(reduce.configure(w, h, w / k, h / k, channels));
    EXPECT_EQ(reduce.factor(), k);
    reduce.run(src.data, src.step, got.data, got.step);
    EXPECT_EQ(cv::norm(want, got, cv::NORM_INF), 0.0) << w << "x" << h << " / " << k;
}

// A smooth gradient: neighbouring cells differ little, so a rounding difference would
// show as a byte off in many places.
cv::Mat ramp(int w, int h, int channels) {
    cv::Mat m(h, w, CV_8UC(channels));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w * channels; ++x)
            m.ptr<std::uint8_t>(y)[x] = static_cast<std::uint8_t>((x * 7 + y * 3) % 256);
    return m;
}

void expect_like_area_mean(const cv::Mat& src, int dw, int dh) {
    cv::Mat want, got(dh, dw, src.type(), cv::Scalar::all(7));
    cv::resize(src, want, got.size(), 0, 0, cv::INTER_AREA);
    AreaMean reduce;
    ASSERT_TRUE(reduce.configure(src.cols, src.rows, dw, dh, src.channels()));
    ASSERT_TRUE(reduce.ready());
    reduce.run(src.data, src.step, got.data, got.step);
    cv::Mat diff;
    cv::absdiff(want, got, diff);
    EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0)
        << src.cols << "x" << src.rows << " -> " << dw << "x" << dh << " (" << src.channels()
        << " channels), largest difference " << cv::norm(want, got, cv::NORM_INF);
}

}  // namespace

TEST(BlockMean, OddFactorsGiveTheInterAreaBytes) {
    expect_like_inter_area(1920, 1080, 3, 3);
    expect_like_inter_area(1000, 600, 5, 3);
    expect_like_inter_area(630, 357, 7, 1);
    expect_like_inter_area(960, 540, 3, 1);
    expect_like_inter_area(64, 48, 1, 3);  // a copy
}

// Even factors round ties: up at 2 (OpenCV's own 2 x 2 path), to even at 4, 6, 8.
// Random bytes make ties common (a quarter of 2 x 2 sums end in .5).
TEST(BlockMean, EvenFactorsGiveTheInterAreaBytes) {
    expect_like_inter_area(640, 480, 2, 3);
    expect_like_inter_area(1280, 720, 2, 3);
    expect_like_inter_area(1920, 1080, 6, 3);
    expect_like_inter_area(1280, 720, 4, 3);
    expect_like_inter_area(1920, 1080, 8, 1);
    expect_like_inter_area(98, 14, 2, 1);
}

TEST(BlockMean, RefusesWhatIsNotAnIntegerFactor) {
    BlockMean reduce;
    EXPECT_FALSE(reduce.configure(3840, 2160, 240, 135, 3));  // 16: past the table
    EXPECT_FALSE(reduce.configure(1920, 1080, 640, 361, 3));  // rows not 3 x
    EXPECT_FALSE(reduce.configure(1000, 600, 640, 384, 3));   // not an integer
    EXPECT_FALSE(reduce.configure(1920, 1080, 0, 0, 3));
    EXPECT_FALSE(reduce.ready());
    std::uint8_t untouched = 9;
    reduce.run(nullptr, 0, &untouched, 1);  // not ready: does nothing
    EXPECT_EQ(untouched, 9);
}

// The analysis width is 320: PAL (720x576: 2.25), the sznitman clip (384x288: 1.2), an
// odd size, and rows that are not an integer factor while columns are.
TEST(AreaMean, NonIntegerFactorsGiveTheInterAreaBytes) {
    for (const int channels : {3, 1}) {
        expect_like_area_mean(noise(384, 288, channels, 1), 320, 240);
        expect_like_area_mean(noise(720, 576, channels, 2), 320, 256);
        expect_like_area_mean(noise(1000, 700, channels, 3), 320, 224);
        expect_like_area_mean(noise(1920, 1088, channels, 4), 320, 181);
        expect_like_area_mean(ramp(384, 288, channels), 320, 240);
        expect_like_area_mean(ramp(1366, 768, channels), 320, 180);
    }
}

TEST(AreaMean, IntegerFactorsGoThroughTheBlockPath) {
    expect_like_area_mean(noise(1920, 1080, 3, 5), 320, 180);
    expect_like_area_mean(noise(640, 480, 3, 6), 320, 240);
    expect_like_area_mean(noise(320, 240, 3, 7), 320, 240);  // a copy
}

TEST(AreaMean, RefusesWhatInterAreaDoesNotReduce) {
    AreaMean reduce;
    EXPECT_FALSE(reduce.configure(320, 240, 640, 480, 3));    // enlarging: interpolated
    EXPECT_FALSE(reduce.configure(640, 240, 320, 480, 3));    // one direction enlarged
    EXPECT_FALSE(reduce.configure(3840, 2160, 240, 135, 3));  // integer 16: past BlockMean
    EXPECT_FALSE(reduce.configure(1920, 1080, 0, 0, 3));
    EXPECT_FALSE(reduce.ready());
    std::uint8_t untouched = 9;
    reduce.run(nullptr, 0, &untouched, 1);  // not ready: does nothing
    EXPECT_EQ(untouched, 9);
}

// run() reads the configured source size: a caller must not hand it another frame.
TEST(AreaMean, FitsOnlyTheConfiguredSourceSize) {
    AreaMean reduce;
    ASSERT_TRUE(reduce.configure(720, 576, 320, 256, 3));
    EXPECT_TRUE(reduce.fits(720, 576));
    EXPECT_FALSE(reduce.fits(1920, 1080));
    EXPECT_FALSE(reduce.fits(720, 575));
    ASSERT_TRUE(reduce.configure(1920, 1080, 320, 180, 3));  // the block path
    EXPECT_TRUE(reduce.fits(1920, 1080));
    EXPECT_FALSE(reduce.fits(720, 576));
    EXPECT_FALSE(AreaMean{}.fits(0, 0));
}
