// MaskOps: each operation gives the bytes (values) of the OpenCV call it replaces, on
// random blobs and grey images, borders included.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "endotower/vision/mask_ops.hpp"

using namespace endotower::vision;

namespace {

BytePlane plane(cv::Mat& m) {
    return {m.data, m.cols, m.rows, static_cast<std::size_t>(m.step)};
}

// Random filled discs and bars (some touching the border), 0 / 255.
cv::Mat blobs(int w, int h, int seed) {
    cv::Mat m(h, w, CV_8U, cv::Scalar(0));
    cv::RNG rng(static_cast<std::uint64_t>(seed));
    for (int i = 0; i < 25; ++i) {
        const cv::Point c(rng.uniform(-5, w + 5), rng.uniform(-5, h + 5));
        if (i % 2)
            cv::circle(m, c, rng.uniform(1, 20), cv::Scalar(255), cv::FILLED);
        else
            cv::line(m, c, c + cv::Point(rng.uniform(-60, 60), rng.uniform(-60, 60)),
                     cv::Scalar(255), rng.uniform(1, 9));
    }
    for (int i = 0; i < 200; ++i) m.at<std::uint8_t>(rng.uniform(0, h), rng.uniform(0, w)) ^= 255;
    return m;
}

}  // namespace

TEST(MaskOps, LitFieldIsBlurThresholdAndMoments) {
    for (const cv::Size size : {cv::Size(640, 360), cv::Size(37, 11), cv::Size(5, 3)}) {
        cv::Mat gray(size, CV_8U);
        cv::RNG(size.width).fill(gray, cv::RNG::UNIFORM, 0, 256);
        cv::GaussianBlur(gray, gray, cv::Size(0, 0), 3);  // smooth, so the threshold cuts shapes
        MaskOps ops;
        ops.configure(size.width, size.height);
        for (int t : {0, 12, 100, 127, 128, 200, 254, 255}) {
            cv::Mat want, got(size, CV_8U);
            cv::blur(gray, want, cv::Size(9, 9));
            cv::threshold(want, want, t, 255, cv::THRESH_BINARY);
            const LitMoments m = ops.lit_field(plane(gray), t, plane(got));
            EXPECT_EQ(cv::norm(want, got, cv::NORM_INF), 0.0) << size << " t " << t;
            const cv::Moments mo = cv::moments(want, true);
            EXPECT_EQ(m.m00, mo.m00);
            EXPECT_EQ(m.m10, mo.m10);
            EXPECT_EQ(m.m01, mo.m01);
        }
    }
}

TEST(MaskOps, MorphIsErodeAndDilateWithTheEllipseAndOpenWithTheSquare) {
    const int ellipse[7] = {0, 2, 3, 3, 3, 2, 0};
    const cv::Mat element = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7));
    for (int seed = 1; seed <= 4; ++seed) {
        cv::Mat m = blobs(seed == 4 ? 9 : 320, seed == 4 ? 5 : 200, seed), got(m.size(), CV_8U);
        MaskOps ops;
        ops.configure(m.cols, m.rows);
        cv::Mat want;
        cv::erode(m, want, element);
        ops.morph(plane(m), plane(got), ellipse, true);
        EXPECT_EQ(cv::norm(want, got, cv::NORM_INF), 0.0) << "erode " << seed;
        cv::dilate(m, want, element);
        ops.morph(plane(m), plane(got), ellipse, false);
        EXPECT_EQ(cv::norm(want, got, cv::NORM_INF), 0.0) << "dilate " << seed;
        cv::morphologyEx(m, want, cv::MORPH_OPEN,
                         cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
        ops.open3(plane(m), plane(m));  // in place
        EXPECT_EQ(cv::norm(want, m, cv::NORM_INF), 0.0) << "open " << seed;
    }
}

TEST(MaskOps, LabelsAreOpenCvsComponentsWithTheirStats) {
    for (int seed = 1; seed <= 4; ++seed) {
        cv::Mat m = blobs(320, 200, seed + 10);
        cv::Mat want_labels, stats, centroids;
        const int want = cv::connectedComponentsWithStats(m, want_labels, stats, centroids, 8);
        MaskOps ops;
        ops.configure(m.cols, m.rows);
        cv::Mat got_labels(m.size(), CV_32S);
        const int n = ops.label(plane(m), got_labels.ptr<std::int32_t>(0));
        ASSERT_EQ(n, want) << seed;
        ASSERT_EQ(ops.components().size(), static_cast<std::size_t>(n));
        // The same partition: one OpenCV label per own label and back.
        std::vector<int> to(n, -1), from(n, -1), first(n, -1);
        int mismatches = 0;
        for (int y = 0; y < m.rows; ++y)
            for (int x = 0; x < m.cols; ++x) {
                const int a = got_labels.at<int>(y, x), b = want_labels.at<int>(y, x);
                if (first[a] < 0) first[a] = y * m.cols + x;
                if (to[a] < 0) to[a] = b;
                if (from[b] < 0) from[b] = a;
                mismatches += to[a] != b || from[b] != a;
            }
        EXPECT_EQ(mismatches, 0) << seed;
        EXPECT_EQ(to[0], 0);
        for (int a = 2; a < n; ++a)  // numbered by first pixel in raster order
            EXPECT_LT(first[a - 1], first[a]) << a;
        for (int a = 1; a < n; ++a) {
            const Component& c = ops.components()[a];
            const int b = to[a];
            EXPECT_EQ(c.area, stats.at<int>(b, cv::CC_STAT_AREA));
            EXPECT_EQ(c.left, stats.at<int>(b, cv::CC_STAT_LEFT));
            EXPECT_EQ(c.top, stats.at<int>(b, cv::CC_STAT_TOP));
            EXPECT_EQ(c.right - c.left + 1, stats.at<int>(b, cv::CC_STAT_WIDTH));
            EXPECT_EQ(c.bottom - c.top + 1, stats.at<int>(b, cv::CC_STAT_HEIGHT));
        }
    }
}

// A part of a larger image labelled in place: the labels written into the larger
// image's rows (nothing outside the part touched), the boxes in its coordinates; the
// same labels and stats as the part labelled on its own.
TEST(MaskOps, APartIsLabelledInPlaceWithItsBoxesInTheWholeImage) {
    cv::Mat m = blobs(320, 200, 31);
    const cv::Rect part(37, 21, 150, 120);
    cv::Mat crop = m(part).clone();  // labelled alone
    MaskOps alone, in_place;
    alone.configure(m.cols, m.rows);
    in_place.configure(m.cols, m.rows);
    cv::Mat want(crop.size(), CV_32S), got(m.size(), CV_32S, cv::Scalar(-7));
    const int n = alone.label(plane(crop), want.ptr<std::int32_t>(0));
    cv::Mat view = m(part);
    const BytePlane p{view.data, view.cols, view.rows, static_cast<std::size_t>(view.step)};
    ASSERT_EQ(in_place.label(p, got.ptr<std::int32_t>(part.y) + part.x,
                             static_cast<std::size_t>(m.cols), part.x, part.y),
              n);
    ASSERT_GT(n, 3);
    EXPECT_EQ(cv::norm(got(part), want, cv::NORM_INF), 0.0);
    cv::Mat outside = got.clone();
    outside(part).setTo(-7);
    EXPECT_EQ(cv::countNonZero(outside != -7), 0);
    for (int a = 1; a < n; ++a) {
        const Component& w = alone.components()[a];
        const Component& g = in_place.components()[a];
        EXPECT_EQ(g.area, w.area);
        EXPECT_EQ(g.left, w.left + part.x);
        EXPECT_EQ(g.right, w.right + part.x);
        EXPECT_EQ(g.top, w.top + part.y);
        EXPECT_EQ(g.bottom, w.bottom + part.y);
    }
}

// The most runs a mask can have (every other pixel of every row set, odd width):
// label() works on runs, sized for ceil(w / 2) of them a row. A checkerboard is one
// 8-connected component; every other column alone is one per column.
TEST(MaskOps, TheMostRunsAMaskCanHave) {
    for (const bool checker : {true, false}) {
        cv::Mat m(9, 15, CV_8U, cv::Scalar(0));
        for (int y = 0; y < m.rows; ++y)
            for (int x = checker ? y % 2 : 0; x < m.cols; x += 2) m.at<std::uint8_t>(y, x) = 255;
        MaskOps ops;
        ops.configure(m.cols, m.rows);
        cv::Mat labels(m.size(), CV_32S);
        const int n = ops.label(plane(m), labels.ptr<std::int32_t>(0));
        cv::Mat want;
        ASSERT_EQ(n, cv::connectedComponents(m, want, 8)) << checker;
        ASSERT_EQ(n, checker ? 2 : 9);  // with the background
        EXPECT_EQ(ops.components()[1].area, checker ? 68 : 9);
        EXPECT_EQ(labels.at<int>(8, 14), checker ? 1 : 8);
    }
}

TEST(MaskOps, ChamferInAComponentsBoxIsTheDistanceTransform) {
    for (int seed = 1; seed <= 3; ++seed) {
        cv::Mat m = blobs(320, 200, seed + 20);
        cv::Mat dist, labels, stats, centroids;
        cv::distanceTransform(m, dist, cv::DIST_L2, 3);
        const int n = cv::connectedComponentsWithStats(m, labels, stats, centroids, 8);
        MaskOps ops;
        ops.configure(m.cols, m.rows);
        std::vector<std::uint32_t> out(static_cast<std::size_t>(m.cols) * m.rows);
        int checked = 0, mismatches = 0;
        for (int i = 1; i < n; ++i) {
            const int x0 = std::max(0, stats.at<int>(i, cv::CC_STAT_LEFT) - 1),
                      y0 = std::max(0, stats.at<int>(i, cv::CC_STAT_TOP) - 1);
            const int x1 = std::min(m.cols, stats.at<int>(i, cv::CC_STAT_LEFT) +
                                                stats.at<int>(i, cv::CC_STAT_WIDTH) + 1),
                      y1 = std::min(m.rows, stats.at<int>(i, cv::CC_STAT_TOP) +
                                                stats.at<int>(i, cv::CC_STAT_HEIGHT) + 1);
            ops.chamfer(plane(m), x0, y0, x1, y1, out.data());
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    if (labels.at<int>(y, x) != i) continue;
                    const float d =
                        static_cast<float>(
                            out[static_cast<std::size_t>(y - y0) * (x1 - x0) + x - x0]) *
                        (1.0f / 65536.0f);
                    ++checked;
                    mismatches += d != dist.at<float>(y, x);
                }
        }
        EXPECT_GT(checked, 1000);
        EXPECT_EQ(mismatches, 0) << seed;
    }
}

TEST(MaskOps, SmoothAtLeastIsTheGaussianThresholdAndMask) {
    for (const cv::Size size : {cv::Size(640, 360), cv::Size(23, 9), cv::Size(3, 3)}) {
        cv::Mat in(size, CV_8U), mask = blobs(size.width, size.height, 5);
        cv::RNG(size.area()).fill(in, cv::RNG::UNIFORM, 0, 256);
        // Large flat patches too (saturated sums), and the whole of `mask` where small.
        in(cv::Rect(0, 0, size.width / 2, size.height / 2)).setTo(255);
        if (size.width < 40) mask.setTo(255);
        MaskOps ops;
        ops.configure(size.width, size.height);
        for (int t : {0, 1, 100, 128, 200, 255}) {
            cv::Mat want, got(size, CV_8U);
            cv::GaussianBlur(in, want, cv::Size(5, 5), 1.2);
            cv::threshold(want, want, t - 1, 255, cv::THRESH_BINARY);
            cv::bitwise_and(want, mask, want);
            ops.smooth_at_least(plane(in), t, plane(mask), plane(got));
            EXPECT_EQ(cv::norm(want, got, cv::NORM_INF), 0.0) << size << " t " << t;
        }
        // The blurred bytes themselves, on request (the likelihood tracker sums them).
        cv::Mat want, got(size, CV_8U), smoothed(size, CV_8U);
        cv::GaussianBlur(in, want, cv::Size(5, 5), 1.2);
        ops.smooth_at_least(plane(in), 128, plane(mask), plane(got), plane(smoothed));
        EXPECT_EQ(cv::norm(want, smoothed, cv::NORM_INF), 0.0) << size;
    }
}
