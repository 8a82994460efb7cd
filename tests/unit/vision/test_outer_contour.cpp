// ContourTracer: the largest outer border is cv::findContours' (RETR_EXTERNAL,
// CHAIN_APPROX_SIMPLE) vertex for vertex, the hull has cv::convexHull's vertices, and
// area and perimeter are cv::contourArea's and cv::arcLength's, on random masks.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <set>

#include "endotower/vision/outer_contour.hpp"

using namespace endotower::vision;

namespace {

// Random bars, discs and single pixels; small enough that blobs touch, merge and
// leave holes, one-pixel-wide parts and diagonal steps.
cv::Mat random_mask(int seed) {
    cv::RNG rng(static_cast<std::uint64_t>(seed));
    const int w = rng.uniform(3, 90), h = rng.uniform(3, 70);
    cv::Mat m(h, w, CV_8U, cv::Scalar(0));
    const int shapes = rng.uniform(1, 8);
    for (int i = 0; i < shapes; ++i) {
        const cv::Point c(rng.uniform(-3, w + 3), rng.uniform(-3, h + 3));
        if (i % 3 == 0)
            cv::circle(m, c, rng.uniform(1, 15), cv::Scalar(255), cv::FILLED);
        else
            cv::line(m, c, c + cv::Point(rng.uniform(-40, 40), rng.uniform(-40, 40)),
                     cv::Scalar(255), rng.uniform(1, 5));
    }
    for (int i = rng.uniform(0, 30); i > 0; --i)
        m.at<std::uint8_t>(rng.uniform(0, h), rng.uniform(0, w)) ^= 255;
    return m;
}

std::set<std::pair<int, int>> as_set(const std::vector<cv::Point>& p) {
    std::set<std::pair<int, int>> s;
    for (const cv::Point& q : p) s.insert({q.x, q.y});
    return s;
}

}  // namespace

TEST(ContourTracer, LargestBorderAndHullAreOpenCvs) {
    ContourTracer tracer;
    tracer.reserve(90, 70);
    int compared = 0;
    for (int seed = 1; seed <= 1500; ++seed) {
        const cv::Mat m = random_mask(seed);
        cv::Mat bordered(m.rows + 2, m.cols + 2, CV_8U, cv::Scalar(0));
        m.copyTo(bordered(cv::Rect(1, 1, m.cols, m.rows)));
        std::vector<std::vector<cv::Point>> contours;
        cv::findContours(bordered, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
        const std::vector<cv::Point>* want = nullptr;
        double want_area = 0;
        for (const auto& c : contours) {
            const double a = std::abs(cv::contourArea(c));
            if (c.size() >= 3 && a > want_area) want = &c, want_area = a;
        }
        double area = -1;
        const auto got = tracer.largest(m.data, m.cols, m.rows, m.step, area);
        SCOPED_TRACE("seed " + std::to_string(seed));
        if (want == nullptr) {
            EXPECT_TRUE(got.empty());
            continue;
        }
        ASSERT_EQ(got.size(), want->size());
        for (std::size_t i = 0; i < got.size(); ++i) {
            ASSERT_EQ(got[i].x, (*want)[i].x) << i;
            ASSERT_EQ(got[i].y, (*want)[i].y) << i;
        }
        EXPECT_EQ(area, want_area);
        EXPECT_EQ(polygon_perimeter(got), cv::arcLength(*want, true));
        std::vector<cv::Point> want_hull;
        cv::convexHull(*want, want_hull);
        const auto hull = tracer.hull(got);
        std::vector<cv::Point> got_hull;
        for (const IntPoint& p : hull) got_hull.emplace_back(p.x, p.y);
        EXPECT_EQ(as_set(got_hull), as_set(want_hull));
        EXPECT_EQ(got_hull.size(), want_hull.size());
        EXPECT_EQ(polygon_area(hull), std::abs(cv::contourArea(want_hull)));
        EXPECT_EQ(polygon_perimeter(hull), cv::arcLength(want_hull, true));
        ++compared;
    }
    EXPECT_GT(compared, 1000);
}

TEST(ContourTracer, RefusesMasksLargerThanReservedAndEmptyOnes) {
    ContourTracer tracer;
    tracer.reserve(8, 8);
    std::vector<std::uint8_t> m(16 * 16, 255);
    double area = -1;
    EXPECT_TRUE(tracer.largest(m.data(), 16, 16, 16, area).empty());
    EXPECT_EQ(area, 0.0);
    std::vector<std::uint8_t> zero(8 * 8, 0);
    EXPECT_TRUE(tracer.largest(zero.data(), 8, 8, 8, area).empty());
    // A 3 x 2 block: the border through the pixel centres, a 2 x 1 rectangle.
    zero[8 * 3 + 2] = zero[8 * 3 + 3] = zero[8 * 3 + 4] = zero[8 * 4 + 2] = zero[8 * 4 + 3] =
        zero[8 * 4 + 4] = 1;
    const auto c = tracer.largest(zero.data(), 8, 8, 8, area);
    EXPECT_EQ(c.size(), 4u);
    EXPECT_EQ(area, 2.0);
    EXPECT_EQ(polygon_perimeter(c), 6.0);
    EXPECT_EQ(c[0].x, 3);  // the first pixel, in bordered coordinates
    EXPECT_EQ(c[0].y, 4);
}

// holes(): the two largest background regions the border cannot reach, as OpenCV finds
// them (flood fill of the background from outside, then 4-connected components of what
// is left), on random masks; nothing after a refused mask.
TEST(ContourTracer, HolesAreTheBackgroundTheBorderCannotReach) {
    ContourTracer tracer;
    tracer.reserve(90, 70);
    int with_holes = 0, with_two = 0;
    for (int seed = 0; seed < 400; ++seed) {
        const cv::Mat m = random_mask(seed);
        double area = 0;
        tracer.largest(m.data, m.cols, m.rows, m.step, area);
        int first = -1, second = -1;
        tracer.holes(first, second);

        cv::Mat outside;
        cv::copyMakeBorder(m, outside, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(0));
        cv::floodFill(outside, cv::Point(0, 0), cv::Scalar(128), nullptr, cv::Scalar(0),
                      cv::Scalar(0), 4);
        const cv::Mat inside = outside == 0;
        cv::Mat labels, stats, centroids;
        const int n = cv::connectedComponentsWithStats(inside, labels, stats, centroids, 4);
        std::vector<int> areas;
        for (int i = 1; i < n; ++i) areas.push_back(stats.at<int>(i, cv::CC_STAT_AREA));
        std::sort(areas.rbegin(), areas.rend());
        areas.resize(std::max<std::size_t>(areas.size(), 2), 0);
        EXPECT_EQ(first, areas[0]) << "seed " << seed;
        EXPECT_EQ(second, areas[1]) << "seed " << seed;
        with_holes += first > 0;
        with_two += second > 0;
    }
    EXPECT_GT(with_holes, 40);  // the masks do leave holes, and pairs of them
    EXPECT_GT(with_two, 10);
    std::vector<std::uint8_t> big(100 * 100, 255);
    double area = 0;
    tracer.largest(big.data(), 100, 100, 100, area);  // refused: larger than reserved
    int first = -1, second = -1;
    tracer.holes(first, second);
    EXPECT_EQ(first, 0);
    EXPECT_EQ(second, 0);
}
