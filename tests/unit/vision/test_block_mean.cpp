// BlockMean: the integer-factor reduction gives cv::resize's INTER_AREA bytes.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "endotower/vision/block_mean.hpp"

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

}  // namespace

TEST(BlockMean, OddFactorsGiveTheInterAreaBytes) {
    expect_like_inter_area(1920, 1080, 3, 3);
    expect_like_inter_area(1000, 600, 5, 3);
    expect_like_inter_area(630, 357, 7, 1);
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
