// Anchored overlays (issue 7): the overlay kinds' syntax, the image's corners and the
// tissue pose under a known homography (exact truth), and the draw list on a region
// that leaves the picture and comes back (hidden while lost, back when found), with
// the SCI after it taking its image box target from the tracked region (issue 8).
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "endotower/app/json_line.hpp"
#include "endotower/app/log.hpp"
#include "endotower/app/overlay_canvas.hpp"
#include "endotower/sci/sci_stage.hpp"
#include "endotower/vision/anchored_overlay.hpp"
#include "endotower/vision/anchored_overlay_stage.hpp"
#include "endotower/vision/region_stage.hpp"
#include "region_test_util.hpp"

namespace endotower::vision {
namespace {

using test::texture;

hal::Frame view(cv::Mat& img, std::uint64_t seq) {
    hal::Frame f;
    f.format = {img.cols, img.rows, static_cast<int>(img.step), hal::PixelFormat::kBgr24};
    f.data = img.data;
    f.sequence = seq;
    f.capture_ns = static_cast<hal::Nanos>(seq) * 40'000'000;
    return f;
}

const std::vector<Point2> kSquare{{220, 160}, {420, 170}, {410, 330}, {230, 320}};
const hal::SceneCamera kCamera{500, 480, 321.5, 238.2, 5, 500};

TEST(RegionOverlay, Kinds) {
    RegionOverlay o;
    std::string error;
    ASSERT_TRUE(parse_region_overlay("image:ct/liver.png", o, error)) << error;
    EXPECT_EQ(o.kind, RegionOverlayKind::kImage);
    EXPECT_EQ(o.image, "ct/liver.png");
    ASSERT_TRUE(parse_region_overlay("object:cube", o, error)) << error;
    EXPECT_EQ(o.kind, RegionOverlayKind::kObject);
    ASSERT_TRUE(parse_region_overlay("markers", o, error)) << error;
    EXPECT_EQ(o.kind, RegionOverlayKind::kMarkers);
    EXPECT_FALSE(parse_region_overlay("image:../secret.png", o, error));
    EXPECT_NE(error.find("inside the media folder"), std::string::npos) << error;
    EXPECT_FALSE(parse_region_overlay("image:a/../../b.png", o, error));
    EXPECT_FALSE(parse_region_overlay("image:/etc/passwd", o, error));
    EXPECT_FALSE(parse_region_overlay("image:", o, error));
    EXPECT_FALSE(parse_region_overlay("object:teapot", o, error));
    EXPECT_NE(error.find("unknown object 'teapot'"), std::string::npos) << error;
    EXPECT_FALSE(parse_region_overlay("sticker", o, error));
    EXPECT_NE(error.find("expected markers, image:PATH or object:cube"), std::string::npos)
        << error;
}

// The marking frame's camera sees the tissue plane fronto-parallel at 80 mm; the
// endoscope then rotates by `rvec` about the region's centre and moves by `dt`. The
// homography of the marked box's corners (through float, as OpenCV computes it) is
// what a perfect tracker reports.
struct KnownMotion {
    cv::Matx33d k{kCamera.fx, 0, kCamera.cx, 0, kCamera.fy, kCamera.cy, 0, 0, 1};
    cv::Vec3d rvec{0.25, -0.35, 0.4}, dt{6, -4, 15};
    cv::Matx33d r;
    cv::Vec3d origin, origin_now;
    RegionEstimate e;
    KnownMotion() {
        cv::Rodrigues(rvec, r);
        e.id = 0, e.state = RegionState::kTracked, e.vertices = kSquare.size();
        for (std::size_t i = 0; i < kSquare.size(); ++i) e.marked[i] = kSquare[i];
        const double uc = (220 + 420) / 2.0, vc = (160 + 330) / 2.0;  // the marked box's centre
        origin = {(uc - kCamera.cx) / kCamera.fx * 80, (vc - kCamera.cy) / kCamera.fy * 80, 80};
        origin_now = origin + dt;
        std::vector<cv::Point2f> before, after;
        for (auto [u, v] : {std::pair{220., 160.}, {420., 160.}, {420., 330.}, {220., 330.}}) {
            const cv::Vec3d p((u - kCamera.cx) / kCamera.fx * 80,
                              (v - kCamera.cy) / kCamera.fy * 80, 80);
            const cv::Vec3d q = r * (p - origin) + origin_now;
            before.emplace_back(static_cast<float>(u), static_cast<float>(v));
            after.emplace_back(static_cast<float>(kCamera.fx * q[0] / q[2] + kCamera.cx),
                               static_cast<float>(kCamera.fy * q[1] / q[2] + kCamera.cy));
        }
        const cv::Matx33d h(cv::getPerspectiveTransform(before, after));
        for (int i = 0; i < 9; ++i) e.homography[static_cast<std::size_t>(i)] = h.val[i];
    }
    cv::Point2d map(double x, double y) const {
        cv::Matx33d h;
        for (int i = 0; i < 9; ++i) h.val[i] = e.homography[static_cast<std::size_t>(i)];
        const cv::Vec3d p = h * cv::Vec3d(x, y, 1);
        return {p[0] / p[2], p[1] / p[2]};
    }
};

// A 100x50 image in the 200x170 box: 200x100, centred vertically (y 195..295).
TEST(AnchoredOverlay, ImageCornersAreTheFittedBoxThroughTheHomography) {
    KnownMotion m;
    std::array<Point2, 4> c{};
    ASSERT_TRUE(anchored_image_corners(m.e, 100, 50, c));
    const double xs[4] = {220, 420, 420, 220}, ys[4] = {195, 195, 295, 295};
    for (std::size_t k = 0; k < 4; ++k) {
        const cv::Point2d want = m.map(xs[k], ys[k]);
        EXPECT_NEAR(c[k].x, want.x, 1e-9) << k;
        EXPECT_NEAR(c[k].y, want.y, 1e-9) << k;
    }
    RegionEstimate at_mark = m.e;
    at_mark.homography = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    ASSERT_TRUE(anchored_image_corners(at_mark, 100, 50, c));
    EXPECT_DOUBLE_EQ(c[2].x, 420);
    EXPECT_DOUBLE_EQ(c[2].y, 295);
}

// The cube from the tracked homography lands where the true pose puts it: every vertex
// within 1 px of cv::projectPoints of the truth (the pose is exact up to rounding).
TEST(AnchoredOverlay, CubeFollowsTheTissuePoseWithinOnePixel) {
    KnownMotion m;
    TissuePose pose;
    ASSERT_TRUE(tissue_pose(m.e, kCamera, 80, pose));
    EXPECT_NEAR(pose.origin_mm.x, m.origin_now[0], 1e-4);
    EXPECT_NEAR(pose.origin_mm.y, m.origin_now[1], 1e-4);
    EXPECT_NEAR(pose.origin_mm.z, m.origin_now[2], 1e-4);
    EXPECT_NEAR(pose.width_mm, 200 / kCamera.fx * 80, 1e-9);
    EXPECT_NEAR(pose.height_mm, 170 / kCamera.fy * 80, 1e-9);
    const hal::SceneBox box = anchored_cube(pose, {});
    const double edge = std::min(pose.width_mm, pose.height_mm) / 2;
    EXPECT_FLOAT_EQ(box.size_mm, static_cast<float>(edge));
    // Truth: the cube on the plane (plane z 0 .. -edge, towards the camera at marking).
    std::vector<cv::Point3d> model;
    for (int v = 0; v < 8; ++v)
        model.emplace_back(v & 1 ? edge / 2 : -edge / 2, v & 2 ? edge / 2 : -edge / 2,
                           v & 4 ? 0.0 : -edge);
    std::vector<cv::Point2d> truth;
    cv::projectPoints(model, m.rvec, m.origin_now, m.k, cv::noArray(), truth);
    const auto& a = box.camera_from_model;  // column-major; the box's model is centred
    double worst = 0;
    for (int v = 0; v < 8; ++v) {
        const double x = v & 1 ? edge / 2 : -edge / 2, y = v & 2 ? edge / 2 : -edge / 2,
                     z = v & 4 ? edge / 2 : -edge / 2;
        const double cx = a[0] * x + a[4] * y + a[8] * z + a[12];
        const double cy = a[1] * x + a[5] * y + a[9] * z + a[13];
        const double cz = a[2] * x + a[6] * y + a[10] * z + a[14];
        const cv::Point2d uv(kCamera.fx * cx / cz + kCamera.cx, kCamera.fy * cy / cz + kCamera.cy);
        worst = std::max(worst, cv::norm(uv - truth[static_cast<std::size_t>(v)]));
    }
    EXPECT_LT(worst, 1.0);
    EXPECT_LT(worst, 1e-3);  // float storage of the transform is the only loss
    // No camera: no pose.
    EXPECT_FALSE(tissue_pose(m.e, hal::SceneCamera{}, 80, pose));
}

// A pan takes both regions out of the picture and back: the image (region 0) and the
// cube (region 1) are in the draw list exactly on the frames their region is tracked,
// nowhere while it is lost, and come back when it is found.
TEST(AnchoredOverlayStage, HiddenWhileLostBackWhenFound) {
    const cv::Mat scene = texture(1400, 480, 11);
    auto frame_at = [&](int x) { return scene(cv::Rect(x, 0, 640, 480)).clone(); };
    RegionTracker t;
    RegionStage regions(t);
    regions.schedule({0, 0, kSquare, {RegionOverlayKind::kImage, "a.png"}});
    regions.schedule(
        {0, 1, {{80, 60}, {200, 60}, {200, 150}, {80, 150}}, {RegionOverlayKind::kObject, {}}});
    app::StderrLog log;
    AnchoredOverlayStage anchored(regions, nullptr, log);
    const std::vector<std::uint8_t> px(4 * 8 * 4, 200);
    anchored.set_image(0, {8, 4, 32, px.data()});
    anchored.set_camera(kCamera);
    const hal::FrameFormat format{640, 480, 640 * 3, hal::PixelFormat::kBgr24};
    regions.configure(format);
    anchored.configure(format);
    // The SCI after them (issue 8): its image box target rides on the tracked region.
    sci::SciStage sci_stage({}, nullptr, nullptr, nullptr, log);
    sci_stage.set_camera(kCamera);
    sci_stage.set_target_source(&anchored);
    sci_stage.configure(format);
    app::OverlayCanvas canvas;
    canvas.configure(640, 480);
    app::JsonLine line;
    std::vector<int> pan;
    for (int x = 0; x <= 700; x += 70) pan.push_back(x);
    for (int x = 700; x >= 0; x -= 70) pan.push_back(x);
    int lost_frames = 0, back_frames = 0;
    bool was_lost = false;
    for (std::size_t i = 0; i < pan.size(); ++i) {
        cv::Mat img = frame_at(pan[i]);
        canvas.clear();
        line.clear();
        line.begin_object();
        app::AnalysisContext ctx{view(img, i), {}, canvas, line, 0};
        regions.process(ctx);
        anchored.process(ctx);
        sci_stage.process(ctx);
        line.end_object();
        Vec3 on_tissue;
        if (anchored.target_mm(on_tissue)) {
            EXPECT_DOUBLE_EQ(sci_stage.machine().box_target_mm().x, on_tissue.x);
            EXPECT_DOUBLE_EQ(sci_stage.machine().box_target_mm().z, on_tissue.z);
        }
        ASSERT_EQ(regions.estimates().size(), 2u);
        const bool image_tracked = regions.estimates()[0].state == RegionState::kTracked;
        const bool cube_tracked = regions.estimates()[1].state == RegionState::kTracked;
        EXPECT_EQ(anchored.scene().images.count, image_tracked ? 1u : 0u) << "pan " << pan[i];
        EXPECT_EQ(anchored.scene().boxes.count, cube_tracked ? 1u : 0u) << "pan " << pan[i];
        const std::string json(line.view());
        EXPECT_NE(json.find(image_tracked ? "\"kind\":\"image\",\"shown\":true"
                                          : "\"kind\":\"image\",\"shown\":false"),
                  std::string::npos)
            << json;
        if (image_tracked && pan[i] <= 280) {
            // On the tissue: the fitted image's corners follow the pan (x - pan), while
            // at least 70 % of the region is in the picture (as RegionTracker's test).
            const hal::SceneImage& im = anchored.scene().images.items[0];
            EXPECT_NEAR(im.corners[0].x, 220 + 0.5 - pan[i], 1.5) << "pan " << pan[i];
            EXPECT_NEAR(im.corners[2].x, 420 + 0.5 - pan[i], 1.5) << "pan " << pan[i];
        }
        if (!image_tracked) ++lost_frames, was_lost = true;
        if (was_lost && image_tracked) ++back_frames;
    }
    EXPECT_GT(lost_frames, 0);
    EXPECT_GT(back_frames, 0);
    // The SCI's target: region 0 when tracked (the lowest id), on the tissue at 80 mm.
    Vec3 target;
    ASSERT_TRUE(anchored.target_mm(target));
    EXPECT_NEAR(target.z, 80, 1.0);
}

}  // namespace
}  // namespace endotower::vision
