#include "endotower/scene/camera.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace endotower::scene {
namespace {

TEST(SceneCamera, IntrinsicsFromTheSpec) {
    const CameraModel c = make_camera(CameraSpec{}, 640, 480);
    EXPECT_NEAR(c.fx, 0.868 * 480, 1e-9);
    EXPECT_NEAR(c.fy / c.fx, 65.83 / 66.67, 1e-12);
    EXPECT_NEAR(c.cx, 319.5 + 0.0125 * 480, 1e-9);  // off the sensor centre
    EXPECT_NEAR(c.cy, 239.5 - 0.0083 * 480, 1e-9);
    ASSERT_EQ(c.k.size(), 2u);
    EXPECT_NEAR(c.k[0], -0.32 / (480.0 * 480.0), 1e-18);
    // The same lens at 1080 rows: same angles, pixels scaled.
    const CameraModel h = make_camera(CameraSpec{}, 1920, 1080);
    EXPECT_NEAR(h.fx / c.fx, 1080.0 / 480.0, 1e-12);
}

TEST(SceneCamera, DistortionIsBarrelAndRadial) {
    const CameraModel c = make_camera(CameraSpec{}, 640, 480);
    double xd, yd;
    c.distort(c.cx + 200, c.cy, xd, yd);
    EXPECT_LT(xd - c.cx, 200.0);   // barrel: pulled towards the centre
    EXPECT_NEAR(yd, c.cy, 1e-12);  // the polar angle is kept
    const double r = 200, expected = r * (1 + c.k[0] * r * r + c.k[1] * r * r * r * r);
    EXPECT_NEAR(xd - c.cx, expected, 1e-9);
    c.distort(c.cx, c.cy, xd, yd);
    EXPECT_EQ(xd, c.cx);
    EXPECT_EQ(yd, c.cy);
}

TEST(SceneCamera, UndistortInvertsDistortWithinAHundredthOfAPixel) {
    for (auto [w, h] : {std::pair{640, 480}, std::pair{1920, 1080}}) {
        const CameraModel c = make_camera(CameraSpec{}, w, h);
        double worst = 0;
        for (int y = 0; y < h; y += 7)
            for (int x = 0; x < w; x += 7) {
                if (!c.in_fov(x, y)) continue;
                double xu, yu, xd, yd;
                ASSERT_TRUE(c.undistort(x, y, xu, yu)) << x << "," << y;
                c.distort(xu, yu, xd, yd);
                worst = std::max(worst, std::hypot(xd - x, yd - y));
                // And the other way round, from the undistorted point.
                double xu2, yu2;
                ASSERT_TRUE(c.undistort(xd, yd, xu2, yu2));
                worst = std::max(worst, std::hypot(xu2 - xu, yu2 - yu));
            }
        EXPECT_LT(worst, 0.01) << w << "x" << h;
    }
}

TEST(SceneCamera, ProjectionIsThePinholeThenTheDistortion) {
    const CameraModel c = make_camera(CameraSpec{}, 640, 480);
    double xu, yu, xd, yd, xd2, yd2;
    ASSERT_TRUE(c.project_undistorted({10, -5, 50}, xu, yu));
    EXPECT_NEAR(xu, c.cx + c.fx * 10 / 50, 1e-12);
    EXPECT_NEAR(yu, c.cy + c.fy * -5 / 50, 1e-12);
    ASSERT_TRUE(c.project({10, -5, 50}, xd, yd));
    c.distort(xu, yu, xd2, yd2);
    EXPECT_EQ(xd, xd2);
    EXPECT_EQ(yd, yd2);
    EXPECT_FALSE(c.project({1, 1, -5}, xd, yd));
}

TEST(SceneCamera, NoInverseBeyondTheFoldOfTheLens) {
    CameraSpec s;
    s.k = {-1.0};  // r_d = r (1 - r^2) folds at r = 1/sqrt(3) image heights
    const CameraModel c = make_camera(s, 640, 480);
    EXPECT_NEAR(c.max_undistorted_radius(), 480 / std::sqrt(3.0), 0.6);
    double xu, yu;
    EXPECT_FALSE(c.undistort(c.cx + 0.5 * 480, c.cy, xu, yu));  // past r_d max = 0.385 H
    EXPECT_TRUE(c.undistort(c.cx + 0.3 * 480, c.cy, xu, yu));
}

}  // namespace
}  // namespace endotower::scene
