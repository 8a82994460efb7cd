// The book's calibration (ch. 2, appendix I, ch. 3): its printed figures, and its
// procedure run on simulator frames whose camera is known exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "calib_test_util.hpp"
#include "endotower/calibration/field_of_view.hpp"
#include "endotower/calibration/radial_polynomial.hpp"
#include "endotower/calibration/separation_table.hpp"
#include "endotower/calibration/square_grid.hpp"

namespace endotower::calibration::test {
namespace {

// Appendix I, table AI.1: five (r, dr) pairs, dr = k1 r + k2 r^3.
TEST(BookAppendixI, FitGivesThePrintedCoefficientsAndError) {
    const std::vector<RadialSample> s = {{28, 0}, {56, 1}, {84, 2}, {112, 4}, {140, 6}};
    RadialFit fit;
    std::string error;
    ASSERT_TRUE(fit_radial_polynomial(s, 3, fit, error)) << error;
    ASSERT_EQ(fit.poly.k.size(), 2u);
    EXPECT_NEAR(fit.poly.k[0], 0.013084138, 0.5e-9);
    EXPECT_NEAR(fit.poly.k[1], 0.000001575, 0.5e-9);
    EXPECT_NEAR(fit.total_error, 0.1445, 0.5e-4);
    // Table 2.4's order-1 entry comes from the same data.
    ASSERT_TRUE(fit_radial_polynomial(s, 1, fit, error)) << error;
    EXPECT_NEAR(fit.total_error, 1.9909, 0.5e-4);
    // ... and so do its order-5 and order-7 entries (0.04196, 0.04113; our order 7
    // gives 0.041135, the book's last digit truncated).
    ASSERT_TRUE(fit_radial_polynomial(s, 5, fit, error)) << error;
    EXPECT_NEAR(fit.total_error, 0.04196, 0.5e-5);
    ASSERT_TRUE(fit_radial_polynomial(s, 7, fit, error)) << error;
    EXPECT_NEAR(fit.total_error, 0.04113, 1e-5);
}

const char* kWhite = R"(
frames: 3
light: 0.7
target: {kind: white, distances_mm: 40}
)";

// The chart of table 2.3 (8 mm pitch, 4 mm squares), at the book's 50 mm for the
// focal length, then at its five test distances.
const char* kChart = R"(
frames: 6
light: 0.9
target: {kind: squares, pitch_mm: 8, size_mm: 4, cols: 15, rows: 13, distances_mm: [50, 40, 60, 70, 80, 90]}
)";

// The white-background frame's circle (fig. 2.6), as every later step uses it.
FovCircle white_fov(std::string& error) {
    scene::SceneRenderer white;
    FovCircle fov;
    if (!white.init(scenario_or_fail(kWhite), 26, error)) return fov;
    scene::FrameTruth truth;
    if (!detect_fov_circle(render_gray(white, 0, truth), fov, error)) fov = {};
    return fov;
}

// Fig. 2.6 on the simulator: the illuminated circle's centre within 1 px of the
// truth's field-of-view centre, on every frame (noise differs per frame).
TEST(BookFieldOfView, CentreWithinOnePixelOnSimulatorFrames) {
    for (const char* size : {"640x480", "1280x720"}) {
        scene::Scenario sc = scenario_or_fail(kWhite);
        std::sscanf(size, "%dx%d", &sc.width, &sc.height);
        scene::SceneRenderer r;
        std::string error;
        ASSERT_TRUE(r.init(sc, 26, error)) << error;
        for (int i = 0; i < r.frames(); ++i) {
            scene::FrameTruth truth;
            FovCircle fov;
            ASSERT_TRUE(detect_fov_circle(render_gray(r, i, truth), fov, error)) << error;
            EXPECT_NEAR(fov.cx, r.camera().fov_cx, 1.0) << size << " frame " << i;
            EXPECT_NEAR(fov.cy, r.camera().fov_cy, 1.0) << size << " frame " << i;
            EXPECT_NEAR(fov.radius, r.camera().fov_radius, 1.0) << size << " frame " << i;
        }
    }
}

// The real endoscopic frame of endoseg_fov: our circle's centre within 3 px of the
// centre of its field-of-view mask (computed here from the mask's pixels).
TEST(BookFieldOfView, CentreWithinThreePixelsOfTheEndosegMask) {
    const std::string dir = shared_data("endoseg_fov");
    if (!std::filesystem::is_directory(dir))
        GTEST_SKIP() << "no real data at " << dir << " (../shared/data absent)";
    GrayImage frame, mask;
    std::string error;
    ASSERT_TRUE(load_gray_image(dir + "/demo.jpg", frame, error)) << error;
    ASSERT_TRUE(load_gray_image(dir + "/exemplary_seg.png", mask, error)) << error;
    double sx = 0, sy = 0, n = 0;
    for (int y = 0; y < mask.height; ++y)
        for (int x = 0; x < mask.width; ++x)
            if (mask.at(x, y) > 127) sx += x, sy += y, n += 1;
    ASSERT_GT(n, 0);
    FovCircle fov;
    ASSERT_TRUE(detect_fov_circle(frame, fov, error)) << error;
    EXPECT_NEAR(fov.cx, sx / n, 3.0);
    EXPECT_NEAR(fov.cy, sy / n, 3.0);
}

TEST(BookFieldOfView, NoCircleNamesTheImage) {
    GrayImage flat{64, 48, std::vector<std::uint8_t>(64 * 48, 128), "flat.png"};
    FovCircle fov;
    std::string error;
    EXPECT_FALSE(detect_fov_circle(flat, fov, error));
    EXPECT_NE(error.find("flat.png"), std::string::npos) << error;
    EXPECT_NE(error.find("no illuminated circle"), std::string::npos) << error;
    // A bright square is not a circle.
    GrayImage square{64, 48, std::vector<std::uint8_t>(64 * 48, 0), "square.png"};
    for (int y = 8; y < 40; ++y)
        for (int x = 16; x < 48; ++x) square.pixels[y * 64 + x] = 255;
    EXPECT_FALSE(detect_fov_circle(square, fov, error));
    EXPECT_NE(error.find("square.png"), std::string::npos) << error;
}

struct ChartFrame {
    double distance_mm = 0;
    std::vector<Point2> centres;
    CentreSquares grid;
    scene::FrameTruth truth;
};

// Renders the chart at 50, 40, 60, 70, 80, 90 mm and runs the book's steps on it.
void chart_frames(const FovCircle& fov, std::vector<ChartFrame>& out,
                  const scene::CameraModel** camera, scene::SceneRenderer& r) {
    std::string error;
    ASSERT_TRUE(r.init(scenario_or_fail(kChart), 23, error)) << error;
    *camera = &r.camera();
    for (int i = 0; i < r.frames(); ++i) {
        ChartFrame f;
        const GrayImage g = render_gray(r, i, f.truth);
        f.distance_mm = f.truth.target.distance_mm;
        ASSERT_TRUE(detect_square_centres(g, fov, f.centres, error)) << error;
        ASSERT_TRUE(find_centre_squares(f.centres, {fov.cx, fov.cy}, f.grid, error)) << error;
        out.push_back(std::move(f));
    }
}

// Eq. 2.4 and 2.17 at 50 mm, then table 2.3: the distance computed from the
// spacing of the central squares (eq. 2.2) within 3 mm of the truth at 40-90 mm.
TEST(BookSimulator, Table23DistancesWithinThreeMillimetres) {
    std::string error;
    const FovCircle fov = white_fov(error);
    ASSERT_TRUE(fov.valid()) << error;
    scene::SceneRenderer r;
    const scene::CameraModel* cam = nullptr;
    std::vector<ChartFrame> frames;
    chart_frames(fov, frames, &cam, r);
    ASSERT_EQ(frames.size(), 6u);
    ASSERT_EQ(frames[0].distance_mm, 50);
    // Sx/Sy = Dx/Dy (eq. 2.4) is the camera's fx/fy within 0.5%.
    EXPECT_NEAR(frames[0].grid.sx_over_sy, cam->fx / cam->fy, 0.005 * cam->fx / cam->fy);
    // f from the 50 mm chart (eq. 2.17) within 2% of fx: the central squares are not
    // quite free of barrel distortion, as the book assumes.
    const double f = focal_from_spacing(frames[0].grid.dx, 8, 50);
    EXPECT_NEAR(f, cam->fx, 0.02 * cam->fx);
    for (std::size_t i = 1; i < frames.size(); ++i) {
        const double z = distance_from_spacing(frames[i].grid.dx, 8, f);
        std::printf("table 2.3: actual %.0f mm, calculated %.2f mm\n", frames[i].distance_mm, z);
        EXPECT_NEAR(z, frames[i].distance_mm, 3.0);
    }
}

// Table 2.4's trend and table 2.5's result on the simulator's barrel distortion
// (known exactly): total error falls with the order and changes negligibly past 3;
// the order-3 corrected radii are within 0.5 px of the actual (ideal grid) radii and
// of the truth's undistorted radii (up to the one scale the linear term absorbs).
TEST(BookSimulator, Table24TrendAndTable25CorrectedRadii) {
    std::string error;
    const FovCircle fov = white_fov(error);
    ASSERT_TRUE(fov.valid()) << error;
    scene::SceneRenderer r;
    const scene::CameraModel* cam = nullptr;
    std::vector<ChartFrame> frames;
    chart_frames(fov, frames, &cam, r);
    for (const ChartFrame& f : frames) {
        if (f.distance_mm != 40 && f.distance_mm != 50) continue;  // the book's 40 mm, and 50
        double total[4];
        BookDistortion bd3;
        for (int k = 0; k < 4; ++k) {
            BookDistortion bd;
            ASSERT_TRUE(fit_book_distortion(f.centres, f.grid, {fov.cx, fov.cy}, 12, 2 * k + 1,
                                            fov.radius, bd, error))
                << error;
            total[k] = bd.fit.total_error;
            if (k == 1) bd3 = bd;
        }
        std::printf("table 2.4 at %.0f mm: %.4f %.4f %.4f %.4f\n", f.distance_mm, total[0],
                    total[1], total[2], total[3]);
        EXPECT_GT(total[0], total[1]);
        EXPECT_GE(total[1], total[2]);
        EXPECT_GE(total[2], total[3] - 1e-9);
        EXPECT_LT(total[1] - total[3], 0.01 * total[0]) << "not negligible past order 3";
        // The centre found is the camera's principal point (the distortion centre).
        EXPECT_NEAR(bd3.fit.poly.cx, cam->cx, 0.5);
        EXPECT_NEAR(bd3.fit.poly.cy, cam->cy, 0.5);
        double sxy = 0, sxx = 0, worst_actual = 0, worst_truth = 0;
        std::vector<std::pair<double, double>> corrected_truth;
        for (std::size_t k = 0; k < bd3.samples.size(); ++k) {
            double rc = 0;
            ASSERT_TRUE(bd3.fit.poly.corrected_radius(bd3.samples[k].r - bd3.samples[k].dr, rc));
            EXPECT_NEAR(rc, bd3.samples[k].r, 0.5)
                << "square at actual radius " << bd3.samples[k].r;
            worst_actual = std::max(worst_actual, std::abs(rc - bd3.samples[k].r));
            // The same square in the truth (nearest displayed point).
            std::size_t t = 0;
            double best = 1e9;
            for (std::size_t j = 0; j < f.truth.target.points_px.size(); ++j) {
                const double d = std::hypot(f.truth.target.points_px[j].x - bd3.measured[k].x,
                                            f.truth.target.points_px[j].y - bd3.measured[k].y);
                if (d < best) best = d, t = j;
            }
            ASSERT_LT(best, 1.0);
            const double rt = std::hypot(f.truth.target.points_px_u[t].x - cam->cx,
                                         f.truth.target.points_px_u[t].y - cam->cy);
            sxy += rc * rt, sxx += rt * rt;
            corrected_truth.push_back({rc, rt});
        }
        const double scale = sxy / sxx;
        EXPECT_NEAR(scale, 1.0, 0.03);
        for (const auto& [rc, rt] : corrected_truth) {
            EXPECT_NEAR(rc, scale * rt, 0.5) << "truth radius " << rt;
            worst_truth = std::max(worst_truth, std::abs(rc - scale * rt));
        }
        std::printf(
            "table 2.5 at %.0f mm: centre (%.2f, %.2f), worst |corrected - actual| %.3f px, vs "
            "truth (scale %.4f) %.3f px\n",
            f.distance_mm, bd3.fit.poly.cx, bd3.fit.poly.cy, worst_actual, scale, worst_truth);
    }
}

TEST(BookRadialFit, BadInput) {
    RadialFit fit;
    std::string error;
    EXPECT_FALSE(fit_radial_polynomial({{28, 0}, {56, 1}}, 5, fit, error));
    EXPECT_NE(error.find("too few points"), std::string::npos) << error;
    EXPECT_FALSE(fit_radial_polynomial({{50, 1}, {50, 1.1}, {50, 0.9}}, 3, fit, error));
    EXPECT_NE(error.find("degenerate"), std::string::npos) << error;
    EXPECT_FALSE(fit_radial_polynomial({{0, 0}, {0, 0}}, 1, fit, error));
    EXPECT_NE(error.find("degenerate"), std::string::npos) << error;
    // Distortion growing faster than the radius: r - dr(r) turns back (folds).
    EXPECT_FALSE(
        fit_radial_polynomial({{50, 5}, {100, 40}, {150, 120}, {200, 240}}, 3, fit, error));
    EXPECT_NE(error.find("not monotonic"), std::string::npos) << error;
    EXPECT_FALSE(fit_radial_polynomial({{50, 1}}, 2, fit, error));
    EXPECT_NE(error.find("must be odd"), std::string::npos) << error;
}

TEST(BookRadialFit, CorrectedRadiusInvertsTheModel) {
    RadialPolynomial p{{0.013084138, 0.000001575}, 0, 0};
    for (double r : {0.0, 10.0, 77.7, 140.0, 200.0}) {
        double back = -1;
        ASSERT_TRUE(p.corrected_radius(p.distorted_radius(r), back));
        EXPECT_NEAR(back, r, 1e-9);
    }
}

// Ch. 3's worked example: 50 px at 70 mm, 40 px at 80 mm; at 74 mm 46 px, 1 mm:4.6 px.
TEST(BookSeparation, The74MillimetreExample) {
    SeparationTable t;
    t.distances_mm = {60, 70, 80, 90};
    t.separation_px = {58, 50, 40, 36};
    std::string error;
    ASSERT_TRUE(t.validate(error)) << error;
    EXPECT_DOUBLE_EQ(t.separation_at(74), 46.0);
    EXPECT_DOUBLE_EQ(t.px_per_mm(74), 4.6);
    EXPECT_DOUBLE_EQ(t.separation_at(70), 50.0);
    EXPECT_DOUBLE_EQ(t.depth_for_separation(46), 74.0);
    // Eq. 3.1: 23 px right of the offset at 74 mm is 5 mm.
    EXPECT_DOUBLE_EQ(t.to_mm(123, 100, 74), 5.0);
    t.separation_px = {58, 50, 52, 36};
    EXPECT_FALSE(t.validate(error));
    EXPECT_NE(error.find("must fall"), std::string::npos) << error;
}

// Figs. 3.3-3.5 on the simulator: the two dots at 18 distances (30-200 mm) give a
// table that falls with distance; the pinhole cross-check with the truth's focal
// length agrees within 3%; interpolating between every other row predicts the
// skipped rows within 3%.
TEST(BookSeparation, TwoDotTableFromSimulatorFrames) {
    std::string error;
    const FovCircle fov = white_fov(error);
    ASSERT_TRUE(fov.valid()) << error;
    scene::SceneRenderer r;
    const std::string path =
        std::string(ENDOTOWER_SOURCE_DIR) + "/board/sim/scenarios/fig33_two_dot.yaml";
    scene::Scenario sc;
    ASSERT_TRUE(scene::load_scenario(path, sc, error)) << error;
    ASSERT_TRUE(r.init(sc, 33, error)) << error;
    SeparationTable table;
    for (int i = 0; i < r.frames(); ++i) {
        scene::FrameTruth truth;
        const GrayImage g = render_gray(r, i, truth);
        Point2 a, b;
        ASSERT_TRUE(detect_two_dots(g, fov, a, b, error)) << error;
        const double sep = std::hypot(a.x - b.x, a.y - b.y);
        const double pin = pinhole_separation(r.camera().fx, 10, truth.target.distance_mm);
        EXPECT_NEAR(sep, pin, 0.03 * pin) << truth.target.distance_mm << " mm";
        table.distances_mm.push_back(truth.target.distance_mm);
        table.separation_px.push_back(sep);
    }
    ASSERT_EQ(table.distances_mm.size(), 18u);
    ASSERT_TRUE(table.validate(error)) << error;
    SeparationTable half;
    for (std::size_t i = 0; i < table.distances_mm.size(); i += 2) {
        half.distances_mm.push_back(table.distances_mm[i]);
        half.separation_px.push_back(table.separation_px[i]);
    }
    for (std::size_t i = 1; i + 1 < table.distances_mm.size(); i += 2)
        EXPECT_NEAR(half.separation_at(table.distances_mm[i]), table.separation_px[i],
                    0.03 * table.separation_px[i]);
}

}  // namespace
}  // namespace endotower::calibration::test
