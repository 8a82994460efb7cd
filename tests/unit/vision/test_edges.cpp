// Edge pairing (ch. 4 initialisation) and the midline Kalman filter (eq. 4.4-4.16).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "endotower/vision/edge_pairing.hpp"
#include "endotower/vision/midline_kalman.hpp"

namespace endotower::vision {
namespace {

// Direction of a segment in degrees, as a line (0..180).
double line_deg(const Segment& s) {
    double d = std::atan2(s.b.y - s.a.y, s.b.x - s.a.x) * 180 / M_PI;
    while (d < 0) d += 180;
    while (d >= 180) d -= 180;
    return d;
}

double line_diff_deg(double a, double b) {
    const double d = std::fmod(std::abs(a - b), 180.0);
    return std::min(d, 180.0 - d);
}

// A dark shaft of `width` px at `angle_deg` through `centre`, on textured tissue.
std::vector<Segment> segments_of_bar(double angle_deg, Point2 centre, double width, cv::Mat* shown = nullptr) {
    cv::Mat img(480, 640, CV_8UC3);
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0, 6);
    for (int y = 0; y < img.rows; ++y)
        for (int x = 0; x < img.cols; ++x) {
            const double v = 20 * std::sin(x * 0.05) * std::cos(y * 0.04);
            img.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(90 + v + noise(rng)),
                                                cv::saturate_cast<uchar>(80 + v + noise(rng)),
                                                cv::saturate_cast<uchar>(190 + v + noise(rng)));
        }
    const double a = angle_deg * M_PI / 180, dx = std::cos(a), dy = std::sin(a);
    const double nx = -dy, ny = dx, h = width / 2, L = 400;
    const cv::Point pts[4] = {
        cv::Point(cvRound((centre.x - dx * L + nx * h) * 16), cvRound((centre.y - dy * L + ny * h) * 16)),
        cv::Point(cvRound((centre.x + dx * L + nx * h) * 16), cvRound((centre.y + dy * L + ny * h) * 16)),
        cv::Point(cvRound((centre.x + dx * L - nx * h) * 16), cvRound((centre.y + dy * L - ny * h) * 16)),
        cv::Point(cvRound((centre.x - dx * L - nx * h) * 16), cvRound((centre.y - dy * L - ny * h) * 16))};
    cv::fillConvexPoly(img, pts, 4, cv::Scalar(40, 40, 45), cv::LINE_AA, 4);
    if (shown) *shown = img;
    cv::Mat gray, edges;
    cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
    cv::GaussianBlur(gray, gray, cv::Size(5, 5), 1.5);
    cv::Canny(gray, edges, 40, 120);
    std::vector<cv::Vec4i> lines;
    cv::HoughLinesP(edges, lines, 1, CV_PI / 360, 60, 60, 10);
    std::vector<Segment> segs;
    for (const auto& l : lines) segs.push_back({{double(l[0]), double(l[1])}, {double(l[2]), double(l[3])}});
    std::sort(segs.begin(), segs.end(), [](const Segment& p, const Segment& q) { return p.length() > q.length(); });
    return segs;
}

TEST(EdgePairing, FindsBothEdgesAndTheMidlineAtEveryOrientation) {
    for (double angle : {0.0, 20.0, 45.0, 70.0, 90.0, 110.0, 135.0, 160.0}) {
        const Point2 c{330, 250};
        const auto segs = segments_of_bar(angle, c, 30.0);
        const EdgePair p = pair_edges(segs);
        ASSERT_TRUE(p.found) << angle;
        EXPECT_LT(line_diff_deg(line_deg(p.midline), angle), 1.0) << angle;
        EXPECT_LT(distance_to_line(c, p.midline), 1.5) << angle;
        EXPECT_NEAR(p.width_px, 30.0, 2.5) << angle;
    }
}

TEST(EdgePairing, TheBooksTenPixelBins) {
    // In order: bin 1's first line (y = 100); a parallel line 103 px away opens bin 2;
    // a line 24 px from bin 1 and 79 px from bin 2 fits neither and is dropped; a
    // piece 3 px from bin 1 joins it; an oblique line is dropped.
    const std::vector<Segment> segs = {
        {{100, 100}, {300, 100}}, {{110, 203}, {200, 203}}, {{120, 124}, {320, 124}},
        {{310, 103}, {400, 103}}, {{50, 300}, {200, 400}}};
    const EdgePair p = pair_edges(segs);
    ASSERT_TRUE(p.found);
    // Bin 1 merged from its leftmost to its rightmost end point.
    EXPECT_DOUBLE_EQ(p.e1.a.x, 100);
    EXPECT_DOUBLE_EQ(p.e1.a.y, 100);
    EXPECT_DOUBLE_EQ(p.e1.b.x, 400);
    EXPECT_DOUBLE_EQ(p.e1.b.y, 103);
    EXPECT_DOUBLE_EQ(p.e2.a.x, 110);
    EXPECT_DOUBLE_EQ(p.e2.b.x, 200);
    EXPECT_DOUBLE_EQ(p.e2.a.y, 203);
}

TEST(EdgePairing, NothingOrOneEdgeIsNotAPair) {
    EXPECT_FALSE(pair_edges({}).found);
    const std::vector<Segment> one = {{{0, 0}, {100, 0}}, {{10, 2}, {90, 3}}};
    EXPECT_FALSE(pair_edges(one).found);
}

TEST(MidlineKalman, TracksAConstantVelocityLine) {
    MidlineKalman kf;
    auto truth = [](int t) { return Segment{{0, 100.0 + 2 * t}, {600, 100.0 + 2 * t + 300 * (0.3 + 0.004 * t)}}; };
    kf.init(truth(0));
    double last_err = 1e9;
    for (int t = 1; t < 40; ++t) {
        const SlopeLine pred = kf.predict();
        const Segment z = truth(t);
        // The prior predicts where the line went; after a few frames it is close.
        const double err = std::max(pred.distance(z.a), pred.distance(z.b));
        if (t > 6) {
            EXPECT_LT(err, 3.0) << t;
        }
        last_err = err;
        EXPECT_TRUE(kf.gate(z)) << t;
        const SlopeLine post = kf.correct(z);
        EXPECT_LT(std::max(post.distance(z.a), post.distance(z.b)), 0.5) << t;
    }
    EXPECT_LT(last_err, 1.0);
}

TEST(MidlineKalman, ARotatingToolPassesTheVerticalWithoutLosingTrack) {
    MidlineKalman kf;
    const Point2 c{320, 240};
    auto truth = [&](int t) {
        const double a = (60.0 + 2.0 * t) * M_PI / 180;  // 60 -> 138 degrees, through 90
        return Segment{{c.x - 200 * std::cos(a), c.y - 200 * std::sin(a)}, {c.x + 200 * std::cos(a), c.y + 200 * std::sin(a)}};
    };
    kf.init(truth(0));
    for (int t = 1; t <= 39; ++t) {
        kf.predict();
        const Segment z = truth(t);
        ASSERT_TRUE(kf.gate(z)) << "frame " << t;
        const SlopeLine post = kf.correct(z);
        EXPECT_LT(std::max(post.distance(z.a), post.distance(z.b)), 1.0) << t;
    }
    EXPECT_FALSE(kf.lost());
}

TEST(MidlineKalman, GatesDistantOrObliqueEdgesAndLosesTrackAfterMisses) {
    MidlineKalmanParams params;
    params.max_missed = 3;
    MidlineKalman kf(params);
    kf.init({{0, 200}, {600, 260}});
    kf.predict();
    EXPECT_TRUE(kf.gate({{0, 215}, {600, 275}}));    // the other edge, 15 px away
    EXPECT_FALSE(kf.gate({{0, 300}, {600, 360}}));   // parallel but 100 px away
    EXPECT_FALSE(kf.gate({{0, 200}, {600, 500}}));   // crossing at a steep angle
    for (int i = 0; i < 3; ++i) {
        kf.miss();
        EXPECT_FALSE(kf.lost());
    }
    kf.miss();
    EXPECT_TRUE(kf.lost());
}

}  // namespace
}  // namespace endotower::vision
