// Anchored overlays rendered headless (issue 7): the image anchored to a region and the
// cube standing on its tissue, under a known endoscope motion, land within 1 px of the
// truth in the read-back pixels (the homography-mapped corners; cv::projectPoints of the
// true pose). Skips when no EGL display / GLES2 context can be had.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "endotower/gles/gles_renderer.hpp"
#include "endotower/vision/anchored_overlay.hpp"

namespace endotower::vision {
namespace {

constexpr int kW = 640, kH = 480;
const hal::SceneCamera kCamera{500, 480, 321.5, 238.2, 5, 500};

class AnchoredRender : public ::testing::Test {
protected:
    void SetUp() override {
        std::string error;
        renderer_ = gles::create_gles_renderer(error);
        if (!renderer_) GTEST_SKIP() << "no EGL display / GLES2 context here: " << error;
        ASSERT_TRUE(renderer_->configure(kW, kH)) << renderer_->error();
        px_.assign(4 * kW * kH, 0);
        layer_ = {kW, kH, 4 * kW, px_.data()};
        // The marked region; the endoscope turns about its centre and moves (as a
        // perfect tracker reports it: the homography of the marked box's corners).
        e_.state = RegionState::kTracked, e_.vertices = 4;
        const Point2 poly[4] = {{220, 160}, {420, 170}, {410, 330}, {230, 320}};
        for (std::size_t i = 0; i < 4; ++i) e_.marked[i] = poly[i];
        cv::Rodrigues(rvec_, r_);
        const cv::Vec3d origin((320 - kCamera.cx) / kCamera.fx * 80,
                               (245 - kCamera.cy) / kCamera.fy * 80, 80);
        origin_now_ = origin + cv::Vec3d(-8, 5, 20);
        std::vector<cv::Point2f> before, after;
        for (auto [u, v] : {std::pair{220., 160.}, {420., 160.}, {420., 330.}, {220., 330.}}) {
            const cv::Vec3d p((u - kCamera.cx) / kCamera.fx * 80,
                              (v - kCamera.cy) / kCamera.fy * 80, 80);
            const cv::Vec3d q = r_ * (p - origin) + origin_now_;
            before.emplace_back(float(u), float(v));
            after.emplace_back(float(kCamera.fx * q[0] / q[2] + kCamera.cx),
                               float(kCamera.fy * q[1] / q[2] + kCamera.cy));
        }
        h_ = cv::Matx33d(cv::getPerspectiveTransform(before, after));
        for (int i = 0; i < 9; ++i) e_.homography[std::size_t(i)] = h_.val[i];
    }
    hal::Rgba8 at(int x, int y) const {
        const std::uint8_t* p = &px_[4 * (std::size_t(y) * kW + std::size_t(x))];
        return {p[0], p[1], p[2], p[3]};
    }
    // The drawn pixels (alpha 255) against the true silhouette, the convex hull of
    // `truth` (OpenCV pixel coordinates): no drawn pixel centre more than 1 px outside
    // it, no undrawn one more than 1 px inside, so its outline, corners included, is
    // within 1 px of the truth. Returns the number of drawn pixels.
    int expect_silhouette_within_one_pixel(const std::vector<cv::Point2f>& truth) const {
        std::vector<cv::Point2f> hull;
        cv::convexHull(truth, hull);
        int drawn = 0;
        double worst_out = 0, worst_in = 0;
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x) {
                const double d = cv::pointPolygonTest(hull, cv::Point2f(float(x), float(y)), true);
                if (at(x, y).a == 255)
                    ++drawn, worst_out = std::max(worst_out, -d);
                else
                    worst_in = std::max(worst_in, d);
            }
        EXPECT_LE(worst_out, 1.0) << "a drawn pixel outside the true silhouette";
        EXPECT_LE(worst_in, 1.0) << "an undrawn pixel inside the true silhouette";
        return drawn;
    }
    std::unique_ptr<hal::OverlayRenderer> renderer_;
    std::vector<std::uint8_t> px_;
    hal::OverlayLayer layer_;
    RegionEstimate e_;
    cv::Vec3d rvec_{0.2, -0.3, 0.5}, origin_now_;
    cv::Matx33d r_, h_;
};

// The anchored image: its drawn outline within 1 px of the quad of the fitted box's
// corners mapped by H (the corners included), its inside perspective-correct.
TEST_F(AnchoredRender, ImageCornersWithinOnePixelOfTheHomography) {
    constexpr int kS = 64;
    const hal::Rgba8 quadrant[4] = {
        {255, 0, 0, 255}, {0, 255, 0, 255}, {0, 0, 255, 255}, {255, 255, 255, 255}};
    std::vector<std::uint8_t> img(4 * kS * 2 * kS);  // 128 x 64: fitted 200 x 100 at y 195
    for (int y = 0; y < kS; ++y)
        for (int x = 0; x < 2 * kS; ++x) {
            const hal::Rgba8 c = quadrant[x < kS ? (y < kS / 2 ? 0 : 3) : (y < kS / 2 ? 1 : 2)];
            std::uint8_t* p = &img[4 * (std::size_t(y) * 2 * kS + std::size_t(x))];
            p[0] = c.r, p[1] = c.g, p[2] = c.b, p[3] = c.a;
        }
    ASSERT_TRUE(renderer_->set_image(0, {2 * kS, kS, 8 * kS, img.data()}));
    std::array<Point2, 4> corners{};
    ASSERT_TRUE(anchored_image_corners(e_, 2 * kS, kS, corners));
    hal::OverlayScene scene;
    hal::SceneImage im{.image_id = 0, .warped = true};
    for (std::size_t k = 0; k < 4; ++k)
        im.corners[k] = {float(corners[k].x + 0.5), float(corners[k].y + 0.5)};
    scene.images.add(im);
    hal::DrawnRects drawn;
    ASSERT_TRUE(renderer_->render(scene, layer_, drawn)) << renderer_->error();
    const double xs[4] = {220, 420, 420, 220}, ys[4] = {195, 195, 295, 295};
    std::vector<cv::Point2f> truth;
    for (int k = 0; k < 4; ++k) {
        const cv::Vec3d t = h_ * cv::Vec3d(xs[k], ys[k], 1);
        truth.emplace_back(float(t[0] / t[2]), float(t[1] / t[2]));
    }
    EXPECT_GT(expect_silhouette_within_one_pixel(truth), 10000);
    // Inside, perspective-correct: image points away from the quadrant borders are
    // drawn in their quadrant's colour where the homography puts them.
    for (double u = 0.05; u < 1; u += 0.1)
        for (double v = 0.05; v < 1; v += 0.1) {
            const cv::Vec3d t = h_ * cv::Vec3d(220 + 200 * u, 195 + 100 * v, 1);
            const hal::Rgba8 c = at(int(std::lround(t[0] / t[2])), int(std::lround(t[1] / t[2])));
            EXPECT_EQ(c, quadrant[u < 0.5 ? (v < 0.5 ? 0 : 3) : (v < 0.5 ? 1 : 2)])
                << u << ", " << v;
        }
}

// The cube on the tissue: its silhouette within 1 px of the hull of cv::projectPoints of
// the true pose's cube vertices (the image box's camera, eq. 4.28-4.32).
TEST_F(AnchoredRender, CubeWithinOnePixelOfProjectPoints) {
    TissuePose pose;
    ASSERT_TRUE(tissue_pose(e_, kCamera, 80, pose));
    std::array<hal::Rgba8, 6> faces;
    faces.fill({200, 80, 60, 255});
    hal::OverlayScene scene;
    scene.camera = kCamera;
    scene.boxes.add(anchored_cube(pose, faces));
    hal::DrawnRects drawn;
    ASSERT_TRUE(renderer_->render(scene, layer_, drawn)) << renderer_->error();
    const double edge = std::min(pose.width_mm, pose.height_mm) / 2;
    std::vector<cv::Point3d> model;
    for (int v = 0; v < 8; ++v)
        model.emplace_back(v & 1 ? edge / 2 : -edge / 2, v & 2 ? edge / 2 : -edge / 2,
                           v & 4 ? 0.0 : -edge);
    std::vector<cv::Point2d> uv;
    const cv::Matx33d k(kCamera.fx, 0, kCamera.cx, 0, kCamera.fy, kCamera.cy, 0, 0, 1);
    cv::projectPoints(model, rvec_, origin_now_, k, cv::noArray(), uv);
    std::vector<cv::Point2f> truth(uv.begin(), uv.end());
    EXPECT_GT(expect_silhouette_within_one_pixel(truth), 1000);
}

}  // namespace
}  // namespace endotower::vision
