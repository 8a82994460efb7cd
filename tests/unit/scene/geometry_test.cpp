// The rendered pictures against the truth the simulator writes: the geometry is
// checked against itself (docs/truth.md, issue 3).
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "scene_test_util.hpp"

namespace endotower::scene::test {
namespace {

// A green, unlit tool on white paper, no blur, noise or vignetting, jumping between
// poses all over the field of view (the edge, where the distortion is strongest).
const char* kToolOnWhite = R"(
frames: 6
camera: {blur_px: 0, vignetting: 0}
noise: 0
light: 1
target: {kind: white, distances_mm: 90}
tools:
  - tip: grasper
    jaw: closed
    color: [0, 255, 0]
    pivot_mm: [120, -10, 60]
    start: {tip_mm: [-10, 3, 60]}
    motion:
      - {move: [-28, -14, 55], frames: 0}
      - {dwell: 1}
      - {move: [-20, 22, 62], frames: 0}
      - {dwell: 1}
      - {move: [0, 0, 45], frames: 0}
      - {dwell: 1}
      - {move: [8, 25, 70], frames: 0}
      - {dwell: 1}
      - {move: [-27, 2, 52], frames: 0}
      - {dwell: 1}
)";

TEST(SceneGeometry, RenderedTipIsWhereTheTruthProjectsIt) {
    SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(parse_or_fail(kToolOnWhite), 1, error)) << error;
    for (int f = 0; f < r.frames(); ++f) {
        const Rendered out = render_frame(r, f);
        ASSERT_EQ(out.truth.tools.size(), 1u);
        const ToolTruth& t = out.truth.tools[0];
        // The truth's own points agree with the camera model.
        double xd, yd;
        r.camera().distort(t.tip_px_u.x, t.tip_px_u.y, xd, yd);
        EXPECT_NEAR(xd, t.tip_px.x, 1e-3);
        EXPECT_NEAR(yd, t.tip_px.y, 1e-3);
        ASSERT_TRUE(r.camera().in_fov(t.tip_px.x, t.tip_px.y)) << "frame " << f;
        // The tool's pixels: at least half green.
        const double ux = std::cos(t.axis_deg * M_PI / 180), uy = std::sin(t.axis_deg * M_PI / 180);
        double front = 1e9;
        std::vector<cv::Point2d> pts;
        for (int y = 0; y < out.image.rows; ++y)
            for (int x = 0; x < out.image.cols; ++x) {
                const cv::Vec3b p = out.image.at<cv::Vec3b>(y, x);
                if (p[1] > 128 && p[2] < 128) {
                    pts.emplace_back(x, y);
                    front = std::min(front, (x - t.tip_px.x) * ux + (y - t.tip_px.y) * uy);
                }
            }
        ASSERT_GT(pts.size(), 200u);
        // The extreme tip pixel lies on the truth's tip within a pixel along the axis...
        EXPECT_LT(std::abs(front), 1.0) << "frame " << f;
        // ...and the pixels at the very front are centred on it across the axis.
        double side = 0;
        int n = 0;
        for (const cv::Point2d& p : pts) {
            const double along = (p.x - t.tip_px.x) * ux + (p.y - t.tip_px.y) * uy;
            if (along < front + 1.5) {
                side += -(p.x - t.tip_px.x) * uy + (p.y - t.tip_px.y) * ux;
                ++n;
            }
        }
        EXPECT_LT(std::abs(side / n), 1.0) << "frame " << f;
        // The apparent width at the head: the green run across the shaft, 6 px behind it.
        const double cx = t.head_px.x + 6 * ux, cy = t.head_px.y + 6 * uy;
        int run = 0;
        for (double s = -60; s <= 60; s += 0.25) {
            const int x = static_cast<int>(std::lround(cx - s * uy)),
                      y = static_cast<int>(std::lround(cy + s * ux));
            const cv::Vec3b p = out.image.at<cv::Vec3b>(y, x);
            run += p[1] > 128 && p[2] < 128 ? 1 : 0;
        }
        EXPECT_NEAR(run * 0.25, t.width_px, 1.5) << "frame " << f;
    }
}

// `scene --labels`: the per-pixel tool labels are the green pixels, up to the
// anti-aliased boundary (a pixel's label is its centre's surface).
TEST(SceneGeometry, ToolLabelsCoverTheToolsPixels) {
    SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(parse_or_fail(kToolOnWhite), 1, error)) << error;
    std::vector<std::uint8_t> labels;
    for (int f = 0; f < r.frames(); f += 2) {
        const Rendered out = render_frame(r, f);
        r.tool_labels(labels);
        ASSERT_EQ(labels.size(), out.image.total());
        int tool = 0, disagree = 0, other = 0;
        for (int y = 0; y < out.image.rows; ++y)
            for (int x = 0; x < out.image.cols; ++x) {
                const cv::Vec3b p = out.image.at<cv::Vec3b>(y, x);
                const std::uint8_t l = labels[static_cast<std::size_t>(y) * out.image.cols + x];
                const bool green = p[1] > 128 && p[2] < 128;
                tool += l == 1;
                other += l != 0 && l != 1;
                disagree += (l == 1) != green;
            }
        EXPECT_GT(tool, 200) << "frame " << f;
        EXPECT_EQ(other, 0) << "frame " << f;  // one tool, no motion blur
        EXPECT_LT(disagree, 0.06 * tool) << "frame " << f;
    }
}

// Table 6.6's deformation: the truth's outline follows the pushed tissue. A patch of
// texture at a vertex in frame 0 is found again, by template matching in the last
// frame, where the truth puts that vertex (the shipped suite, no camera motion).
TEST(SceneGeometry, DeformedTissueIsWhereTheTruthPutsTheRegion) {
    Scenario sc;
    std::string error;
    ASSERT_TRUE(load_scenario(std::string(ENDOTOWER_SOURCE_DIR) + "/board/sim/scenarios/t66_deformation.yaml", sc, error))
        << error;
    sc.noise = 0;
    SceneRenderer r;
    ASSERT_TRUE(r.init(sc, sc.seed, error)) << error;
    const Rendered first = render_frame(r, 0), last = render_frame(r, r.frames() - 1);
    ASSERT_EQ(last.truth.regions.size(), 1u);
    EXPECT_EQ(last.truth.regions[0].change, "deformation");
    double moved = 0;
    for (std::size_t k = 0; k < first.truth.regions[0].polygon_px.size(); ++k) {
        const Px a = first.truth.regions[0].polygon_px[k], b = last.truth.regions[0].polygon_px[k];
        moved = std::max(moved, std::hypot(b.x - a.x, b.y - a.y));
        cv::Mat gray0, gray1, score;
        cv::cvtColor(first.image, gray0, cv::COLOR_BGR2GRAY);
        cv::cvtColor(last.image, gray1, cv::COLOR_BGR2GRAY);
        const int h = 10, search = 30;
        const cv::Rect patch(cvRound(a.x) - h, cvRound(a.y) - h, 2 * h + 1, 2 * h + 1);
        const cv::Rect window(cvRound(a.x) - search, cvRound(a.y) - search, 2 * search + 1, 2 * search + 1);
        cv::matchTemplate(gray1(window), gray0(patch), score, cv::TM_CCOEFF_NORMED);
        cv::Point best;
        cv::minMaxLoc(score, nullptr, nullptr, nullptr, &best);
        // The patch was cut at the rounded vertex: compare displacements.
        const double fx = window.x + best.x + h - cvRound(a.x), fy = window.y + best.y + h - cvRound(a.y);
        EXPECT_NEAR(fx, b.x - a.x, 1.5) << "vertex " << k;
        EXPECT_NEAR(fy, b.y - a.y, 1.5) << "vertex " << k;
    }
    EXPECT_GT(moved, 6.0);  // the deformation is not negligible at the vertices
}

TEST(SceneGeometry, CheckerboardCornersAreWhereTheTruthSays) {
    const Scenario s = parse_or_fail(R"(
frames: 3
target: {kind: checkerboard, cols: 9, rows: 6, pitch_mm: 4, distances_mm: [55, 65, 80]}
)");
    SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(s, 7, error)) << error;
    for (int f = 0; f < 3; ++f) {
        const Rendered out = render_frame(r, f);
        ASSERT_TRUE(out.truth.has_target);
        EXPECT_EQ(out.truth.target.distance_mm, s.target.distances_mm[f]);
        cv::Mat gray;
        cv::cvtColor(out.image, gray, cv::COLOR_BGR2GRAY);
        std::vector<cv::Point2f> corners;
        ASSERT_TRUE(cv::findChessboardCorners(gray, cv::Size(9, 6), corners)) << "frame " << f;
        cv::cornerSubPix(
            gray, corners, cv::Size(5, 5), cv::Size(-1, -1),
            cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 0.001));
        ASSERT_EQ(out.truth.target.points_px.size(), 54u);
        double worst = 0;
        for (const cv::Point2f& c : corners) {
            double best = 1e9;
            for (const Px& p : out.truth.target.points_px)
                best = std::min(best, std::hypot(c.x - p.x, c.y - p.y));
            worst = std::max(worst, best);
        }
        EXPECT_LT(worst, 0.5) << "frame " << f;
    }
}

TEST(SceneGeometry, TwoDotMarkerCentresAndSeparationOverDistance) {
    // Book fig. 3.3: 10 mm apart, 18 distances 30..200 mm.
    const Scenario s = parse_or_fail(R"(
frames: 18
light: 1
target:
  kind: two_dot
  dot_mm: 3
  separation_mm: 10
  distances_mm: [30, 35, 40, 45, 50, 55, 60, 70, 80, 90, 100, 110, 120, 130, 150, 170, 185, 200]
)");
    SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(s, 3, error)) << error;
    for (int f = 0; f < 18; ++f) {
        const Rendered out = render_frame(r, f);
        const TargetTruth& tg = out.truth.target;
        ASSERT_EQ(tg.points_px.size(), 2u);
        cv::Mat gray, dark;
        cv::cvtColor(out.image, gray, cv::COLOR_BGR2GRAY);
        // Paper brightness varies with distance; the dots are the dark blobs inside it.
        const double paper = cv::mean(gray(cv::Rect(300, 150, 40, 20)))[0];
        cv::Mat circle = cv::Mat::zeros(gray.size(), CV_8U);
        cv::circle(circle, cv::Point(320, 240), 200, cv::Scalar(255), -1);
        cv::threshold(gray, dark, paper / 2, 255, cv::THRESH_BINARY_INV);
        dark &= circle;
        cv::Mat labels, stats, centroids;
        const int n = cv::connectedComponentsWithStats(dark, labels, stats, centroids);
        std::vector<cv::Point2d> blobs;
        // Intensity-weighted centroids over each blob's box (sub-pixel, edge pixels partial).
        for (int i = 1; i < n; ++i) {
            const cv::Rect b(stats.at<int>(i, 0) - 2, stats.at<int>(i, 1) - 2,
                             stats.at<int>(i, 2) + 4, stats.at<int>(i, 3) + 4);
            double sw = 0, sx = 0, sy = 0;
            for (int y = b.y; y < b.y + b.height; ++y)
                for (int x = b.x; x < b.x + b.width; ++x) {
                    const double wgt = std::max(0.0, paper - gray.at<std::uint8_t>(y, x));
                    sw += wgt, sx += wgt * x, sy += wgt * y;
                }
            blobs.emplace_back(sx / sw, sy / sw);
        }
        ASSERT_EQ(blobs.size(), 2u) << "frame " << f;
        if (blobs[0].x > blobs[1].x) std::swap(blobs[0], blobs[1]);
        for (int k = 0; k < 2; ++k) {
            EXPECT_NEAR(blobs[k].x, tg.points_px[k].x, 0.5) << "frame " << f;
            EXPECT_NEAR(blobs[k].y, tg.points_px[k].y, 0.5) << "frame " << f;
        }
        // Separation in pixels falls as 1/z (book fig. 3.5): sep * z = f * 10 mm.
        const double sep = std::hypot(tg.points_px_u[1].x - tg.points_px_u[0].x,
                                      tg.points_px_u[1].y - tg.points_px_u[0].y);
        EXPECT_NEAR(sep * tg.distance_mm, r.camera().fx * 10, 1e-6 * r.camera().fx);
    }
}

TEST(SceneGeometry, RegionHomographyMapsTheFirstOutlineOntoTheCurrentOne) {
    const Scenario s = parse_or_fail(R"(
frames: 12
regions: [{polygon_mm: [[-10, -8], [12, -6], [10, 9], [-8, 7]]}]
endoscope:
  - {translate_mm: [6, -3, 0], frames: 3}
  - {rotate_deg: 20, frames: 3}
  - {zoom: 1.4, frames: 3}
  - {orbit_deg: [12, -8], frames: 3}
)");
    SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(s, 1, error)) << error;
    const CameraModel& cam = r.camera();
    auto undist = [&](Px p) {
        Px u;
        EXPECT_TRUE(cam.undistort(p.x, p.y, u.x, u.y));
        return u;
    };
    const Rendered first = render_frame(r, 0);
    const char* changes[] = {"translation", "rotation", "zoom_in", "planar"};
    for (int f = 1; f < 12; ++f) {
        const Rendered out = render_frame(r, f);
        ASSERT_EQ(out.truth.regions.size(), 1u);
        const RegionTruth& g = out.truth.regions[0];
        EXPECT_EQ(g.change, changes[f / 3 < 4 ? f / 3 : 3]) << "frame " << f;
        const auto& h = g.h_from_first;
        for (std::size_t k = 0; k < g.polygon_px.size(); ++k) {
            const Px a = undist(first.truth.regions[0].polygon_px[k]), b = undist(g.polygon_px[k]);
            const double w = h[6] * a.x + h[7] * a.y + h[8];
            EXPECT_NEAR((h[0] * a.x + h[1] * a.y + h[2]) / w, b.x, 1e-3);
            EXPECT_NEAR((h[3] * a.x + h[4] * a.y + h[5]) / w, b.y, 1e-3);
        }
    }
}

TEST(SceneGeometry, SameSeedSameBytesOtherSeedOtherPicture) {
    const Scenario s = parse_or_fail(R"(
frames: 3
noise: 2
motion_blur: 0.5
smoke: 0.3
flashes: 0.5
tools:
  - {pivot_mm: [80, -60, 20], start: {tip_mm: [0, 5, 75]}, motion: [{wander: 3, speed_cm_s: 10}]}
)");
    auto run = [&](std::uint64_t seed, int frame) {
        SceneRenderer r;
        std::string error;
        EXPECT_TRUE(r.init(s, seed, error)) << error;
        const Rendered out = render_frame(r, frame);
        return std::pair{out.image, truth_json_line(out.truth, r.camera(), s)};
    };
    const auto a = run(5, 2), b = run(5, 2), c = run(6, 2);
    ASSERT_EQ(a.first.total(), b.first.total());
    EXPECT_EQ(0, std::memcmp(a.first.data, b.first.data, a.first.total() * 3));
    EXPECT_EQ(a.second, b.second);
    EXPECT_NE(0, std::memcmp(a.first.data, c.first.data, a.first.total() * 3));
    EXPECT_NE(a.second, c.second);  // the wander path follows the seed
}

TEST(SceneGeometry, GestureLabelsFollowTheJaws) {
    // Two tools whose jaws cross near the centre, then apart.
    const char* kTemplate = R"(
frames: 2
tools:
  - {tip: scissors, jaw: JAW0, pivot_mm: [90, -30, 20], start: {tip_mm: [-4, 2, 70]}, motion: [{dwell: 1}, {move: [-30, 20, 70], frames: 0}]}
  - {tip: grasper, jaw: JAW1, pivot_mm: [-90, -30, 20], start: {tip_mm: [4, 2, 70]}, motion: [{dwell: 1}, {move: [30, 20, 70], frames: 0}]}
)";
    const std::tuple<const char*, const char*, const char*> cases[] = {
        {"closed", "closed", "cross"},
        {"open", "closed", "triangle"},
        {"open", "open", "double_triangle"}};
    for (const auto& [j0, j1, label] : cases) {
        std::string text = kTemplate;
        text.replace(text.find("JAW0"), 4, j0);
        text.replace(text.find("JAW1"), 4, j1);
        SceneRenderer r;
        std::string error;
        ASSERT_TRUE(r.init(parse_or_fail(text), 1, error)) << error;
        EXPECT_EQ(render_frame(r, 0).truth.gesture, label);
        const Rendered apart = render_frame(r, 1);
        EXPECT_EQ(apart.truth.gesture, "");
        EXPECT_EQ(apart.truth.tools[0].gesture, std::string(j0) + "_scissors");
    }
}

TEST(SceneGeometry, SpeedEventsAndOcclusionInTheTruth) {
    const Scenario s = parse_or_fail(R"(
frames: 40
fps: 25
occluders: [{center_mm: [-12, 0, 50], radius_mm: [9, 9]}]
tools:
  - pivot_mm: [80, -40, 20]
    start: {tip_mm: [10, 0, 70]}
    motion:
      - {move: [-14, 0, 70], speed_cm_s: 6}
      - {dwell: 5}
      - {loop: {radius_mm: 5, turns: 1}, frames: 10}
)");
    SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(s, 1, error)) << error;
    // 24 mm at 60 mm/s: 0.4 s = 10 frames of motion at 6 cm/s.
    EXPECT_NEAR(render_frame(r, 3).truth.speed_cm_s, 6.0, 1e-6);
    const Rendered dwell = render_frame(r, 12);
    EXPECT_EQ(dwell.truth.events, std::vector<std::string>{"dwell"});
    EXPECT_NEAR(dwell.truth.speed_cm_s, 0.0, 1e-9);
    // The flap hides part of the tool: less of it is visible than without the flap.
    Scenario bare = s;
    bare.occluders.clear();
    SceneRenderer rb;
    ASSERT_TRUE(rb.init(bare, 1, error)) << error;
    const double without = render_frame(rb, 12).truth.tools[0].visible_fraction;
    EXPECT_LT(dwell.truth.tools[0].visible_fraction, without - 0.1);
    EXPECT_TRUE(dwell.truth.tools[0].visible);
    const Rendered loop = render_frame(r, 20);
    EXPECT_EQ(loop.truth.events, std::vector<std::string>{"loop"});
    // A loop of radius 5 mm in 0.4 s: 2 pi 5 / 0.4 mm/s = 7.85 cm/s (chord per frame).
    EXPECT_NEAR(loop.truth.speed_cm_s, 2 * 5 * std::sin(M_PI / 10) * 25 / 10, 1e-3);
}

}  // namespace
}  // namespace endotower::scene::test
