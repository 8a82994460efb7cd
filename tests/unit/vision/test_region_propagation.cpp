// The region's per-frame propagation, allocation-free (docs/regions.md "Propagation"):
// PyramidLk on images with exact sub-pixel truth (sums of sinusoids, evaluated at the
// warped coordinates), LkPyramid's levels and HighPassWindow against OpenCV's own
// operations, RansacHomography against a known homography with 30 % outliers and
// against cv::findHomography, degenerate input refused, and no heap allocation in
// steady-state frames of RegionTracker's propagation (operator new and the C allocator).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "endotower/vision/region_tracker.hpp"
#include "heap_counter.hpp"
#include "high_pass_window.hpp"
#include "pyramid_lk.hpp"
#include "ransac_homography.hpp"
#include "region_test_util.hpp"

namespace endotower::vision {
namespace {

using detail::HighPassWindow;
using detail::LkParams;
using detail::LkPyramid;
using detail::PyramidLk;
using detail::RansacHomography;

// A texture defined everywhere: eight plane waves, periods 7 to 61 px.
double scene(double x, double y) {
    struct Wave {
        double angle, period, phase, amplitude;
    };
    static constexpr std::array<Wave, 8> kWaves{{{0.3, 7.3, 0.1, 14},
                                                 {1.1, 9.7, 2.0, 16},
                                                 {2.0, 13.1, 4.1, 18},
                                                 {2.7, 17.9, 1.3, 20},
                                                 {0.8, 23.3, 5.2, 22},
                                                 {1.9, 31.7, 0.7, 24},
                                                 {2.4, 43.1, 3.3, 26},
                                                 {0.1, 61.0, 2.2, 28}}};
    double v = 0;
    for (const Wave& w : kWaves)
        v += w.amplitude *
             std::sin(2 * M_PI * (x * std::cos(w.angle) + y * std::sin(w.angle)) / w.period +
                      w.phase);
    return v;
}

// Fills p's base with the scene seen through `inverse` (base pixel -> scene point).
template <class F>
void render(LkPyramid& p, int w, int h, F inverse) {
    float* b = p.base(w, h);
    ASSERT_NE(b, nullptr);
    const std::ptrdiff_t stride = p.level(0).stride;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const cv::Point2d q = inverse(cv::Point2d(x, y));
            b[y * stride + x] = static_cast<float>(scene(q.x, q.y));
        }
    p.build();
}

std::vector<cv::Point2f> grid(int w, int h, int step, int margin) {
    std::vector<cv::Point2f> g;
    for (int y = margin; y < h - margin; y += step)
        for (int x = margin; x < w - margin; x += step)
            g.emplace_back(static_cast<float>(x) + 0.37f, static_cast<float>(y) + 0.61f);
    return g;
}

struct LkResult {
    double worst = 0, mean = 0;
    int found = 0;
};

// Points of `prev` through the truth `forward` into `next`, followed by PyramidLk.
template <class F>
LkResult follow(const LkPyramid& prev, const LkPyramid& next, const std::vector<cv::Point2f>& pts,
                F forward) {
    std::vector<cv::Point2f> out(pts.size());
    std::vector<std::uint8_t> status(pts.size());
    PyramidLk().track(prev, next, pts, out, status);
    LkResult r;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        if (!status[i]) continue;
        const cv::Point2d t = forward(cv::Point2d(pts[i]));
        const double e = std::hypot(out[i].x - t.x, out[i].y - t.y);
        r.worst = std::max(r.worst, e);
        r.mean += e;
        ++r.found;
    }
    r.mean /= std::max(1, r.found);
    return r;
}

class Lk : public ::testing::Test {
protected:
    void SetUp() override {
        prev.reserve(kW, kH, LkParams{});
        next.reserve(kW, kH, LkParams{});
        render(prev, kW, kH, [](cv::Point2d p) { return p; });
    }
    static constexpr int kW = 320, kH = 240;
    LkPyramid prev, next;
};

// A sub-pixel shift, within the window at the base level.
TEST_F(Lk, RecoversASubPixelShift) {
    const cv::Point2d t(2.37, -1.62);
    render(next, kW, kH, [&](cv::Point2d p) { return p - t; });
    const auto pts = grid(kW, kH, 20, 24);
    const LkResult r = follow(prev, next, pts, [&](cv::Point2d p) { return p + t; });
    EXPECT_EQ(r.found, static_cast<int>(pts.size()));
    EXPECT_LT(r.mean, 0.02);
    EXPECT_LT(r.worst, 0.05);  // LK stops at steps below 0.03 px (OpenCV's criterion)
}

// 11.6 px: beyond the 15x15 window at the base level; the pyramid carries it.
TEST_F(Lk, RecoversAShiftLargerThanTheWindowThroughThePyramid) {
    const cv::Point2d t(9.31, 6.77);
    render(next, kW, kH, [&](cv::Point2d p) { return p - t; });
    const auto pts = grid(kW, kH, 20, 30);
    const LkResult r = follow(prev, next, pts, [&](cv::Point2d p) { return p + t; });
    EXPECT_EQ(r.found, static_cast<int>(pts.size()));
    EXPECT_LT(r.mean, 0.02);
    EXPECT_LT(r.worst, 0.05);
}

// Rotation by 2 degrees and zoom by 3 % about the centre, plus a shift: the window's
// translation model is approximate (the motion varies by up to 0.45 px across a window),
// so the bound is looser.
TEST_F(Lk, RecoversAWarp) {
    const double a = 2 * M_PI / 180, s = 1.03;
    const cv::Point2d c(kW / 2.0, kH / 2.0), t(1.4, -0.8);
    const auto forward = [&](cv::Point2d p) {
        const cv::Point2d d = p - c;
        return c + t +
               s * cv::Point2d(std::cos(a) * d.x - std::sin(a) * d.y,
                               std::sin(a) * d.x + std::cos(a) * d.y);
    };
    render(next, kW, kH, [&](cv::Point2d q) {
        const cv::Point2d d = (q - c - t) / s;
        return c + cv::Point2d(std::cos(a) * d.x + std::sin(a) * d.y,
                               -std::sin(a) * d.x + std::cos(a) * d.y);
    });
    const auto pts = grid(kW, kH, 20, 30);
    const LkResult r = follow(prev, next, pts, forward);
    EXPECT_EQ(r.found, static_cast<int>(pts.size()));
    EXPECT_LT(r.mean, 0.1);
    EXPECT_LT(r.worst, 0.25);
}

// A flat window (no texture) and a point whose window leaves the padded image fail.
TEST_F(Lk, FlatWindowsAndPointsOutsideFail) {
    next.reserve(kW, kH, LkParams{});
    float* b = next.base(kW, kH);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            b[y * next.level(0).stride + x] = x < kW / 2 ? 0.f : scene(x, y);
    next.build();
    const std::vector<cv::Point2f> pts{{60, 120}, {260, 120}, {-40, 120}, {kW + 40.f, 120}};
    std::vector<cv::Point2f> out(pts.size());
    std::vector<std::uint8_t> status(pts.size());
    PyramidLk().track(next, next, pts, out, status);
    EXPECT_EQ(status, (std::vector<std::uint8_t>{0, 1, 0, 0}));
    EXPECT_LT(std::hypot(out[1].x - 260, out[1].y - 120), 1e-3);
}

// The levels: OpenCV's sizes, its level-count rule and its pyrDown (to float rounding).
TEST(LkPyramidLevels, MatchOpenCvPyrDown) {
    LkPyramid p;
    p.reserve(301, 203, LkParams{});
    cv::Mat img(203, 301, CV_32F);
    cv::randu(img, 0, 255);
    float* b = p.base(301, 203);
    for (int y = 0; y < img.rows; ++y)
        std::copy_n(img.ptr<float>(y), img.cols, b + y * p.level(0).stride);
    p.build();
    ASSERT_EQ(p.levels(), 4);  // 301x203, 151x102, 76x51, 38x26 (19x13 would be < 15)
    cv::Mat expected = img;
    for (int l = 1; l < p.levels(); ++l) {
        cv::pyrDown(expected, expected);
        const LkPyramid::Level lv = p.level(l);
        ASSERT_EQ(lv.width, expected.cols);
        ASSERT_EQ(lv.height, expected.rows);
        double worst = 0;
        for (int y = 0; y < lv.height; ++y)
            for (int x = 0; x < lv.width; ++x)
                worst = std::max(worst, std::abs(double(lv.at(x, y)) - expected.at<float>(y, x)));
        EXPECT_LT(worst, 1e-3) << "level " << l;
    }
    EXPECT_EQ(p.base(302, 203), nullptr);  // larger than reserved
}

hal::Frame frame_of(cv::Mat& img, hal::PixelFormat pf) {
    hal::Frame f;
    f.format = {img.cols, img.rows, static_cast<int>(img.step), pf};
    f.data = img.data;
    return f;
}

// The high-pass window equals OpenCV's grey, INTER_AREA resize and box blur (in float),
// at the scales the tracker uses (1, an integer factor, and a fractional one).
TEST(HighPassWindow, MatchesOpenCvAtEveryScaleAndFormat) {
    cv::Mat bgr = test::texture(640, 480, 5), rgb, bgra, grey;
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    const cv::Rect roi(37, 41, 301, 257);
    for (const double s : {1.0, 0.5, 0.75, 1.0 / 3}) {
        cv::Mat g, small, mean, expected;
        grey(roi).convertTo(g, CV_32F);
        if (s < 1)
            cv::resize(g, small, cv::Size(), s, s, cv::INTER_AREA);
        else
            small = g;
        cv::blur(small, mean, cv::Size(15, 15));
        expected = small - mean;
        for (auto [img, pf] :
             {std::pair{&bgr, hal::PixelFormat::kBgr24}, std::pair{&rgb, hal::PixelFormat::kRgb24},
              std::pair{&bgra, hal::PixelFormat::kBgra32},
              std::pair{&grey, hal::PixelFormat::kGray8}}) {
            HighPassWindow hp;
            hp.reserve(640, 480, s);
            LkPyramid p;
            p.reserve(hp.scaled({640, 480}).width, hp.scaled({640, 480}).height, LkParams{});
            ASSERT_TRUE(hp.build(frame_of(*img, pf), roi, p));
            const LkPyramid::Level lv = p.level(0);
            ASSERT_EQ(lv.width, expected.cols) << s;
            ASSERT_EQ(lv.height, expected.rows) << s;
            double worst = 0;
            for (int y = 0; y < lv.height; ++y)
                for (int x = 0; x < lv.width; ++x)
                    worst =
                        std::max(worst, std::abs(double(lv.at(x, y)) - expected.at<float>(y, x)));
            EXPECT_LT(worst, 2e-3) << "scale " << s << " format " << hal::to_string(pf);
        }
    }
    HighPassWindow hp;
    hp.reserve(640, 480, 1.0);
    LkPyramid p;
    p.reserve(640, 480, LkParams{});
    EXPECT_FALSE(hp.build(frame_of(bgr, hal::PixelFormat::kBgr24), cv::Rect(600, 0, 64, 64), p));
    EXPECT_FALSE(hp.build(frame_of(bgr, hal::PixelFormat::kBgr24), cv::Rect(), p));
    hal::Frame yuyv = frame_of(bgr, hal::PixelFormat::kYuyv);
    EXPECT_FALSE(hp.build(yuyv, roi, p));
}

// ---- RANSAC

struct Pairs {
    std::vector<cv::Point2f> from, to;
    std::vector<std::uint8_t> outlier;
};

cv::Point2d map(const cv::Matx33d& h, cv::Point2d p) {
    const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1);
    return {q[0] / q[2], q[1] / q[2]};
}

const cv::Matx33d kTruth(0.93, -0.21, 70, 0.19, 0.95, -25, 1.2e-4, -0.8e-4, 1);

// n pairs in 640x480 through kTruth with Gaussian noise; 30 % outliers at least 20 px off.
Pairs pairs(int n, double noise, std::uint64_t seed) {
    cv::RNG rng(seed);
    Pairs p;
    for (int i = 0; i < n; ++i) {
        const cv::Point2d a(rng.uniform(0.0, 640.0), rng.uniform(0.0, 480.0));
        cv::Point2d b = map(kTruth, a) + cv::Point2d(rng.gaussian(noise), rng.gaussian(noise));
        const bool out = i % 10 < 3;
        if (out) {
            const double angle = rng.uniform(0.0, 2 * M_PI), r = rng.uniform(20.0, 200.0);
            b += cv::Point2d(r * std::cos(angle), r * std::sin(angle));
        }
        p.from.emplace_back(a);
        p.to.emplace_back(b);
        p.outlier.push_back(out ? 1 : 0);
    }
    return p;
}

// Mean distance of the 640x480 frame's corners through two homographies.
double corner_distance(const cv::Matx33d& a, const cv::Matx33d& b) {
    double s = 0;
    for (const cv::Point2d c :
         {cv::Point2d(0, 0), cv::Point2d(639, 0), cv::Point2d(639, 479), cv::Point2d(0, 479)}) {
        const cv::Point2d d = map(a, c) - map(b, c);
        s += std::hypot(d.x, d.y) / 4;
    }
    return s;
}

TEST(RansacHomography, RecoversAKnownHomographyWithThirtyPercentOutliers) {
    const Pairs p = pairs(200, 0.0, 11);
    RansacHomography r;
    cv::Matx33d h;
    std::vector<std::uint8_t> mask(p.from.size());
    ASSERT_TRUE(r.fit(p.from, p.to, h, mask));
    EXPECT_LT(corner_distance(h, kTruth), 1e-3);
    EXPECT_EQ(r.inlier_count(), 140);
    for (std::size_t i = 0; i < mask.size(); ++i) EXPECT_NE(mask[i], p.outlier[i]) << i;
    EXPECT_DOUBLE_EQ(h(2, 2), 1.0);
}

// With 0.5 px noise: every inlier found and no outlier, the fit near the truth and near
// OpenCV's findHomography over the inliers (each refits the inliers of its own best
// sample, so the two differ by the noise: about sigma / sqrt(inliers / 8)). On exact
// points the two agree to a thousandth of a pixel.
TEST(RansacHomography, AgreesWithOpenCv) {
    for (const double noise : {0.0, 0.5}) {
        for (const std::uint64_t seed : {1, 2, 3, 4, 5}) {
            const Pairs p = pairs(150, noise, seed);
            RansacHomography r;
            cv::Matx33d h;
            std::vector<std::uint8_t> mask(p.from.size());
            ASSERT_TRUE(r.fit(p.from, p.to, h, mask));
            const cv::Matx33d cv_h(cv::findHomography(p.from, p.to, cv::RANSAC, 3.0));
            double from_truth = 0, from_cv = 0;
            int inliers = 0;
            for (std::size_t i = 0; i < mask.size(); ++i) {
                EXPECT_NE(mask[i], p.outlier[i]) << seed << " pair " << i;
                if (p.outlier[i]) continue;
                const cv::Point2d q = map(h, p.from[i]), t = map(kTruth, p.from[i]),
                                  c = map(cv_h, p.from[i]);
                from_truth += std::hypot(q.x - t.x, q.y - t.y);
                from_cv += std::hypot(q.x - c.x, q.y - c.y);
                ++inliers;
            }
            from_truth /= inliers, from_cv /= inliers;
            std::printf("noise %.1f seed %d: %.4f px from the truth, %.4f px from OpenCV's\n",
                        noise, static_cast<int>(seed), from_truth, from_cv);
            EXPECT_LT(from_truth, noise > 0 ? 0.3 : 1e-4) << seed;
            EXPECT_LT(from_cv, noise > 0 ? 0.15 : 1e-3) << seed;
        }
    }
}

TEST(RansacHomography, TheSameInputGivesTheSameResult) {
    const Pairs p = pairs(120, 0.7, 9);
    RansacHomography r;
    cv::Matx33d a, b;
    std::vector<std::uint8_t> ma(p.from.size()), mb(p.from.size());
    ASSERT_TRUE(r.fit(p.from, p.to, a, ma));
    const int iterations = r.iterations();
    ASSERT_TRUE(RansacHomography().fit(p.from, p.to, b, mb));
    EXPECT_EQ(ma, mb);
    for (int i = 0; i < 9; ++i) EXPECT_EQ(a.val[i], b.val[i]);
    EXPECT_GT(iterations, 0);
    EXPECT_LT(iterations, 500);  // adaptive: 70 % inliers need far fewer than the cap
}

TEST(RansacHomography, RefusesDegenerateInput) {
    RansacHomography r;
    cv::Matx33d h = cv::Matx33d::eye();
    const auto refuses = [&](const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b) {
        std::vector<std::uint8_t> mask(a.size(), 7);
        return !r.fit(a, b, h, mask);
    };
    std::vector<cv::Point2f> line, moved;
    for (int i = 0; i < 50; ++i) {
        line.emplace_back(10.f + 7.3f * i, 20.f + 3.1f * i);
        moved.emplace_back(15.f + 7.0f * i, 22.f + 3.5f * i);
    }
    EXPECT_TRUE(refuses(line, moved)) << "collinear points";
    EXPECT_TRUE(refuses({{0, 0}, {10, 0}, {0, 10}}, {{1, 1}, {11, 1}, {1, 11}})) << "three";
    EXPECT_TRUE(refuses(std::vector<cv::Point2f>(20, {5, 5}), std::vector<cv::Point2f>(20, {6, 6})))
        << "one point";
    std::vector<cv::Point2f> a{{0, 0}, {100, 0}, {100, 100}, {0, 100}, {50, 50}}, b = a;
    b[2].x = NAN;
    EXPECT_TRUE(refuses(a, b)) << "not finite";
    std::vector<std::uint8_t> short_mask(3);
    EXPECT_FALSE(r.fit(a, a, h, short_mask)) << "mask of another size";
    EXPECT_EQ(h, cv::Matx33d::eye());
    // The same five points are a homography (the identity).
    std::vector<std::uint8_t> mask(a.size());
    ASSERT_TRUE(r.fit(a, a, h, mask));
    EXPECT_LT(corner_distance(h, cv::Matx33d::eye()), 1e-6);
}

// ---- no allocation per frame

hal::Frame view(cv::Mat& img, std::uint64_t seq) {
    hal::Frame f = frame_of(img, hal::PixelFormat::kBgr24);
    f.sequence = seq;
    f.capture_ns = static_cast<hal::Nanos>(seq) * 16'666'667;
    return f;
}

// A view of a textured scene panning 5 px and turning 0.3 degrees per frame, so the
// propagation window is redrawn as the region moves.
std::vector<cv::Mat> moving_view(cv::Size s, int n) {
    const cv::Mat scene_img = test::texture(s.width, s.height, 77);
    std::vector<cv::Mat> frames;
    for (int i = 0; i < n; ++i) {
        cv::Mat m =
            cv::getRotationMatrix2D(cv::Point2f(s.width / 2.f, s.height / 2.f), 0.3 * i, 1.0);
        m.at<double>(0, 2) += 5 * i;
        cv::Mat f;
        cv::warpAffine(scene_img, f, m, s, cv::INTER_LINEAR, cv::BORDER_REFLECT);
        frames.push_back(f);
    }
    return frames;
}

// Steady state: after marking and the first frames (keyframe matching, buffers sized),
// frames that only propagate allocate nothing, at 1080p (followed at half size) and
// 640x480 (full size), with OpenCV's default threading.
TEST(RegionPropagation, SteadyStateFramesAllocateNothing) {
    for (const cv::Size size : {cv::Size(1920, 1080), cv::Size(640, 480)}) {
        std::vector<cv::Mat> frames = moving_view(size, 40);
        RegionTracker tracker({.redetect_interval = 0});
        const double w = size.width, h = size.height;
        const std::vector<Point2> region{
            {0.30 * w, 0.35 * h}, {0.47 * w, 0.36 * h}, {0.46 * w, 0.62 * h}, {0.31 * w, 0.60 * h}};
        std::string error;
        ASSERT_TRUE(tracker.mark(0, region, view(frames[0], 0), error)) << error;
        std::array<RegionEstimate, 1> out{};
        for (std::uint64_t i = 1; i < 5; ++i) tracker.track(view(frames[i], i), out);
        int propagated = 0;
        endotower::test::set_counting(true);
        for (std::uint64_t i = 5; i < frames.size(); ++i) {
            tracker.track(view(frames[i], i), out);
            propagated += out[0].state == RegionState::kTracked && !out[0].keyframe_match;
        }
        endotower::test::set_counting(false);
        EXPECT_EQ(propagated, 35) << size;
        if (endotower::test::heap_allocations() < 0)
            GTEST_SKIP() << "not counted under a sanitizer";
        EXPECT_EQ(endotower::test::heap_allocations(), 0) << size << ": operator new in 35 frames";
        EXPECT_EQ(endotower::test::c_allocations(), 0)
            << size << ": C allocator calls in 35 frames";
    }
}

TEST(RegionPropagation, RansacAllocatesNothing) {
    const Pairs p = pairs(150, 0.5, 3);
    RansacHomography r;
    cv::Matx33d h;
    std::vector<std::uint8_t> mask(p.from.size());
    endotower::test::set_counting(true);
    const bool ok = r.fit(p.from, p.to, h, mask);
    endotower::test::set_counting(false);
    EXPECT_TRUE(ok);
    if (endotower::test::heap_allocations() < 0) GTEST_SKIP() << "not counted under a sanitizer";
    EXPECT_EQ(endotower::test::c_allocations(), 0);
}

}  // namespace
}  // namespace endotower::vision
