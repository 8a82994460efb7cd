// StripMarkerTracker (book ch. 3, figs. 3.1-3.2, eq. 3.1-3.2): exact synthetic strips,
// occlusion, bad input, and tables 3.1/3.2 on the simulator (docs/markers.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "endotower/app/json_line.hpp"
#include "endotower/app/overlay_canvas.hpp"
#include "endotower/calibration/field_of_view.hpp"
#include "endotower/calibration/separation_table.hpp"
#include "endotower/scene/renderer.hpp"
#include "endotower/scene/scenario.hpp"
#include "endotower/vision/strip_marker_stage.hpp"
#include "endotower/vision/strip_marker_tracker.hpp"

namespace endotower::vision {
namespace {

constexpr double kFocal = 400;  // synthetic pinhole camera, px

// The pinhole separation table of a 10 mm two-dot marker, 20-200 mm.
calibration::SeparationTable pinhole_table(double focal) {
    calibration::SeparationTable t;
    for (double z = 20; z <= 200; z += 10) {
        t.distances_mm.push_back(z);
        t.separation_px.push_back(focal * 10 / z);
    }
    return t;
}

// A tool along +x from the tip at x = x_tip (row `cy`) out of the right border (the
// shaft leaves the picture), apparent width w0 (+ slope (x - x_tip) when it leans).
// Three dark strips of `strip` px with `gap` px between, the first `offset` px behind
// the tip. Grey tissue around it. The polygon fill covers both boundary rows, so the
// drawn width is one pixel more than the polygon's: width_at() is the drawn one.
struct SyntheticTool {
    int width = 640, height = 480;
    double x_tip = 120, cy = 240, w0 = 40, slope = 0;
    double offset = 60, strip = 24, gap = 24;
    int tissue = 110, metal = 200, black = 25;
    int rim = -1;  // >= 0: the limb, rim_px wide inside the silhouette, in this grey
    double rim_px = 3;

    double width_at(double x) const { return w0 + slope * (x - x_tip) + 1; }
    double polygon_width(double x) const { return w0 + slope * (x - x_tip); }
    double strip_centre(int k) const { return x_tip + offset + k * (strip + gap) + strip / 2; }
    cv::Mat draw() const {
        cv::Mat img(height, width, CV_8UC3, cv::Scalar(tissue, tissue, tissue));
        const double x_end = width + 10;
        const std::vector<cv::Point> body = {
            {int(std::lround(x_tip)), int(std::lround(cy - w0 / 2))},
            {int(std::lround(x_end)), int(std::lround(cy - polygon_width(x_end) / 2))},
            {int(std::lround(x_end)), int(std::lround(cy + polygon_width(x_end) / 2))},
            {int(std::lround(x_tip)), int(std::lround(cy + w0 / 2))}};
        if (rim >= 0) {
            cv::fillConvexPoly(img, body, cv::Scalar(rim, rim, rim), cv::LINE_8);
            const std::vector<cv::Point> inner = {
                {int(std::lround(x_tip)), int(std::lround(cy - w0 / 2 + rim_px))},
                {int(std::lround(x_end)), int(std::lround(cy - polygon_width(x_end) / 2 + rim_px))},
                {int(std::lround(x_end)), int(std::lround(cy + polygon_width(x_end) / 2 - rim_px))},
                {int(std::lround(x_tip)), int(std::lround(cy + w0 / 2 - rim_px))}};
            cv::fillConvexPoly(img, inner, cv::Scalar(metal, metal, metal), cv::LINE_8);
        } else {
            cv::fillConvexPoly(img, body, cv::Scalar(metal, metal, metal), cv::LINE_8);
        }
        for (int k = 0; k < 3; ++k) {
            const double x0 = x_tip + offset + k * (strip + gap), x1 = x0 + strip;
            const std::vector<cv::Point> s = {
                {int(std::lround(x0)), int(std::lround(cy - polygon_width(x0) / 2))},
                {int(std::lround(x1)), int(std::lround(cy - polygon_width(x1) / 2))},
                {int(std::lround(x1)), int(std::lround(cy + polygon_width(x1) / 2))},
                {int(std::lround(x0)), int(std::lround(cy + polygon_width(x0) / 2))}};
            cv::fillConvexPoly(img, s, cv::Scalar(black, black, black), cv::LINE_8);
        }
        return img;
    }
};

hal::Frame frame_of(cv::Mat& bgr) {
    hal::Frame f;
    f.format = {bgr.cols, bgr.rows, static_cast<int>(bgr.step), hal::PixelFormat::kBgr24};
    f.data = bgr.data;
    return f;
}

std::size_t run(StripMarkerTracker& t, cv::Mat& img, std::array<StripMarker, 2>& out) {
    hal::Frame f = frame_of(img);
    t.configure(f.format);
    return t.track(f, std::span<StripMarker, 2>(out));
}

StripMarkerTracker calibrated_tracker(double diameter_mm) {
    StripMarkerParams p;
    p.diameter_mm = diameter_mm;
    StripMarkerTracker t(p);
    t.set_calibration(pinhole_table(kFocal), {kFocal, kFocal, 320, 240},
                      [](Point2 q) { return q; });
    return t;
}

// Known geometry: the strip nearest the tip (farthest from the shaft, which leaves
// the picture) is found with E at its centre, M within 0.5 px of the drawn width, and
// the depth f D / M within 1.5 %.
TEST(StripMarkers, ExactSyntheticStripsGiveKnownDepth) {
    SyntheticTool tool;
    cv::Mat img = tool.draw();
    StripMarkerTracker t = calibrated_tracker(5.0);
    std::array<StripMarker, 2> out;
    ASSERT_EQ(run(t, img, out), 1u);
    const StripMarker& m = out[0];
    EXPECT_EQ(m.strips, 3);
    const double xe = tool.strip_centre(0), we = tool.width_at(xe);
    EXPECT_NEAR(m.e.x, xe, 0.5);
    EXPECT_NEAR(m.e.y, tool.cy, 0.5);
    EXPECT_NEAR(m.diameter_px, we, 0.5);
    ASSERT_TRUE(m.located);
    const double z = kFocal * 5.0 / we;  // 5 mm at `we` px
    EXPECT_NEAR(m.depth_mm, z, 0.015 * z);
    EXPECT_NEAR(m.depth_pinhole_mm, z, 0.015 * z);
    // Eq. 3.1/3.2 with the principal point as offsets.
    EXPECT_NEAR(m.e_mm.x, (xe - 320) * z / kFocal, 0.03 * std::abs((xe - 320) * z / kFocal));
    EXPECT_NEAR(m.e_mm.y, 0.0, 0.1);
    // The trapezoid: AB on the tip side, CD behind it, both about M long.
    EXPECT_LT(m.a.x, m.e.x);
    EXPECT_GT(m.c.x, m.e.x);
    EXPECT_NEAR(std::hypot(m.b.x - m.a.x, m.b.y - m.a.y), tool.width_at(m.a.x), 0.5);
}

// Occlusion (book: "even with occlusion ... of one or two ... strips"): tissue over
// the strip nearest the tip, then over the first two; the nearest visible is used.
TEST(StripMarkers, OneOrTwoOccludedStrips) {
    SyntheticTool tool;
    for (int hidden = 1; hidden <= 2; ++hidden) {
        cv::Mat img = tool.draw();
        for (int k = 0; k < hidden; ++k) {
            const double xc = tool.strip_centre(k);
            cv::circle(img, cv::Point(int(xc), int(tool.cy)), int(tool.strip * 0.5 + 6),
                       cv::Scalar(tool.tissue, tool.tissue, tool.tissue), cv::FILLED);
        }
        StripMarkerTracker t = calibrated_tracker(5.0);
        std::array<StripMarker, 2> out;
        ASSERT_EQ(run(t, img, out), 1u) << hidden << " hidden";
        EXPECT_EQ(out[0].strips, 3 - hidden);
        const double xe = tool.strip_centre(hidden);
        EXPECT_NEAR(out[0].e.x, xe, 0.5) << hidden << " hidden";
        const double z = kFocal * 5.0 / tool.width_at(xe);
        EXPECT_NEAR(out[0].depth_mm, z, 0.015 * z) << hidden << " hidden";
    }
}

// Under the scope's coaxial light the limb darkens to a rim darker than the tissue,
// which the tool-part threshold leaves out; M comes from the silhouettes beyond it.
// A glint (or a chart line) just past the silhouettes, where the profile beside the
// strip reads the background, must not cost those: neighbouring profiles along the
// band give M within 1 px of the drawn width (the threshold's width is 6 px less).
TEST(StripMarkers, DarkLimbAndAGlintBesideTheStrip) {
    SyntheticTool tool;
    tool.rim = 60;
    const double band_x = tool.x_tip + tool.offset + tool.strip;  // strip 0 ends here
    for (const bool glint : {false, true}) {
        cv::Mat img = tool.draw();
        if (glint)
            for (const int sign : {-1, 1}) {
                const int y0 = static_cast<int>(tool.cy) + sign * 25, y1 = y0 + sign * 15;
                cv::rectangle(img, cv::Point(int(band_x) + 1, std::min(y0, y1)),
                              cv::Point(int(band_x) + 6, std::max(y0, y1)),
                              cv::Scalar(240, 240, 240), cv::FILLED);
            }
        StripMarkerTracker t = calibrated_tracker(5.0);
        std::array<StripMarker, 2> out;
        ASSERT_EQ(run(t, img, out), 1u) << "glint " << glint;
        const double xe = tool.strip_centre(0);
        EXPECT_NEAR(out[0].e.x, xe, 1.0) << "glint " << glint;
        EXPECT_NEAR(out[0].e.y, tool.cy, 0.5) << "glint " << glint;
        EXPECT_NEAR(out[0].diameter_px, tool.width_at(xe), 1.0) << "glint " << glint;
    }
}

// Bad input: a tool without strips, a saturated frame, a black frame, a format the
// tracker does not read, a frame of another size than configured: no marker.
TEST(StripMarkers, BadInputGivesNoMarker) {
    std::array<StripMarker, 2> out;
    SyntheticTool plain;
    plain.black = plain.metal;
    cv::Mat img = plain.draw();
    StripMarkerTracker t = calibrated_tracker(5.0);
    EXPECT_EQ(run(t, img, out), 0u);
    cv::Mat white(480, 640, CV_8UC3, cv::Scalar(255, 255, 255));
    EXPECT_EQ(run(t, white, out), 0u);
    cv::Mat black(480, 640, CV_8UC3, cv::Scalar(0, 0, 0));
    EXPECT_EQ(run(t, black, out), 0u);
    SyntheticTool tool;
    cv::Mat good = tool.draw();
    hal::Frame f = frame_of(good);
    t.configure(f.format);
    f.format.pixel_format = hal::PixelFormat::kYuyv;
    EXPECT_EQ(t.track(f, std::span<StripMarker, 2>(out)), 0u);
    f = frame_of(good);
    t.configure({320, 240, 960, hal::PixelFormat::kBgr24});
    EXPECT_EQ(t.track(f, std::span<StripMarker, 2>(out)), 0u);
    // Uncalibrated: found, but not located in millimetres.
    StripMarkerTracker raw;
    ASSERT_EQ(run(raw, good, out), 1u);
    EXPECT_FALSE(out[0].located);
}

// The simulator's camera stands in for the scope's calibration: its exact
// undistortion and principal point (the calibration's own accuracy is measured in
// docs/calibration.md).
struct SimCalibration {
    calibration::SeparationTable table;
    PinholeCamera camera;
    std::function<Point2(Point2)> undistort;
};

hal::Frame frame_of(scene::Image& img) {
    hal::Frame f;
    f.format = {img.width, img.height, img.width * 3, hal::PixelFormat::kBgr24};
    f.data = img.bgr.data();
    return f;
}

// Figs. 3.3-3.5: the two-dot table from the simulator's fig33_two_dot frames (dot
// centres undistorted), as `endotower calibrate --marker` builds it.
bool two_dot_calibration(SimCalibration& cal, std::string& error) {
    scene::Scenario sc;
    if (!scene::load_scenario(
            std::string(ENDOTOWER_SOURCE_DIR) + "/board/sim/scenarios/fig33_two_dot.yaml", sc,
            error))
        return false;
    auto r = std::make_shared<scene::SceneRenderer>();
    if (!r->init(sc, 33, error)) return false;
    const scene::CameraModel& cam = r->camera();
    const calibration::FovCircle fov{cam.fov_cx, cam.fov_cy, cam.fov_radius};
    for (int i = 0; i < r->frames(); ++i) {
        scene::Image img;
        scene::FrameTruth truth;
        r->render(i, img, truth);
        calibration::GrayImage g;
        calibration::gray_from_frame(frame_of(img), g);
        calibration::Point2 a, b;
        if (!calibration::detect_two_dots(g, fov, a, b, error)) return false;
        double ax, ay, bx, by;
        cam.undistort(a.x, a.y, ax, ay);
        cam.undistort(b.x, b.y, bx, by);
        cal.table.distances_mm.push_back(truth.target.distance_mm);
        cal.table.separation_px.push_back(std::hypot(ax - bx, ay - by));
    }
    cal.camera = {cam.fx, cam.fy, cam.cx, cam.cy};
    cal.undistort = [r](Point2 p) {
        Point2 q;
        r->camera().undistort(p.x, p.y, q.x, q.y);
        return q;
    };
    return cal.table.validate(error);
}

// Tables 3.1 and 3.2 on the simulator (board/sim/scenarios/t31_t32_marker_points.yaml):
// the first strip's centre on the book's test points at 30-70 mm over 10 mm grid
// lines on black paper. Per point: depth, x, y against the truth's strip centre.
// Goals (issue 6): depth error <= 3 % mean, x and y <= 5 % mean (book 4.5 %, 19.3 %,
// 15.2 %). x, y errors are relative to the test point's coordinate and taken where it
// is not 0 (as the book's percentages must be).
TEST(StripMarkers, Tables31And32OnTheSimulator) {
    SimCalibration cal;
    std::string error;
    ASSERT_TRUE(two_dot_calibration(cal, error)) << error;
    scene::Scenario sc;
    ASSERT_TRUE(scene::load_scenario(
        std::string(ENDOTOWER_SOURCE_DIR) + "/board/sim/scenarios/t31_t32_marker_points.yaml", sc,
        error))
        << error;
    scene::SceneRenderer r;
    ASSERT_TRUE(r.init(sc, sc.seed, error)) << error;
    StripMarkerParams p;
    p.diameter_mm = sc.tools.at(0).diameter_mm;
    StripMarkerTracker t(p);
    t.set_calibration(cal.table, cal.camera, cal.undistort);
    double ez = 0, ex = 0, ey = 0;
    int nz = 0, nx = 0, ny = 0, found = 0;
    std::printf("point (mm)          depth (mm)   estimate (x, y, z) mm       strips\n");
    for (int i = 0; i < r.frames(); ++i) {
        scene::Image img;
        scene::FrameTruth truth;
        r.render(i, img, truth);
        const hal::Frame f = frame_of(img);
        if (i == 0) t.configure(f.format);
        std::array<StripMarker, 2> out;
        const std::size_t n = t.track(f, std::span<StripMarker, 2>(out));
        ASSERT_FALSE(truth.tools.empty());
        const scene::Vec3 g = truth.tools[0].markers.at(0).center_mm;
        if (n == 0 || !out[0].located) {
            std::printf("(%3.0f, %3.0f) at %2.0f mm: not found\n", g.x, g.y, g.z);
            continue;
        }
        ++found;
        const Vec3 e = out[0].e_mm;
        std::printf("(%3.0f, %3.0f) at %2.0f mm  %6.2f       (%6.2f, %6.2f, %6.2f)  %d\n", g.x, g.y,
                    g.z, e.z, e.x, e.y, e.z, out[0].strips);
        ez += std::abs(e.z - g.z) / g.z, ++nz;
        if (std::abs(g.x) > 0.5) ex += std::abs(e.x - g.x) / std::abs(g.x), ++nx;
        if (std::abs(g.y) > 0.5) ey += std::abs(e.y - g.y) / std::abs(g.y), ++ny;
    }
    // Every test point but one in ten at most (the book's tables have all of them).
    EXPECT_GE(found, 0.9 * r.frames());
    ASSERT_GT(nz, 0);
    std::printf("mean error: depth %.2f %%, x %.2f %%, y %.2f %% over %d points\n", 100 * ez / nz,
                100 * ex / nx, 100 * ey / ny, nz);
    EXPECT_LE(ez / nz, 0.03);
    EXPECT_LE(ex / nx, 0.05);
    EXPECT_LE(ey / ny, 0.05);
}

// The stage's trace member and overlay: calibrated, E in mm as "tip_mm"; without a
// calibration "tip_mm" is null; a frame without a tool gives an empty list.
TEST(StripMarkers, StageWritesTheTraceMember) {
    SyntheticTool tool;
    cv::Mat img = tool.draw();
    cv::Mat empty(480, 640, CV_8UC3, cv::Scalar(110, 110, 110));
    StripMarkerTracker t = calibrated_tracker(5.0);
    StripMarkerTracker raw;
    for (StripMarkerTracker* tracker : {&t, &raw}) {
        StripMarkerStage stage(*tracker);
        stage.configure(frame_of(img).format);
        app::OverlayCanvas canvas;
        canvas.configure(640, 480);
        for (cv::Mat* m : {&img, &empty}) {
            app::JsonLine line;
            line.begin_object();
            canvas.clear();
            app::AnalysisContext ctx{frame_of(*m), {}, canvas, line, 0};
            stage.process(ctx);
            line.end_object();
            const nlohmann::json j = nlohmann::json::parse(line.view());
            ASSERT_TRUE(j.contains("markers")) << line.view();
            if (m == &empty) {
                EXPECT_TRUE(j["markers"].empty()) << line.view();
                EXPECT_EQ(canvas.layer().rect_count, 0u);
                continue;
            }
            ASSERT_EQ(j["markers"].size(), 1u) << line.view();
            const nlohmann::json& k = j["markers"][0];
            const double xe = tool.strip_centre(0), we = tool.width_at(xe), z = kFocal * 5.0 / we;
            EXPECT_NEAR(k["center_px"][0].get<double>(), xe, 0.5);
            EXPECT_NEAR(k["center_px"][1].get<double>(), tool.cy, 0.5);
            EXPECT_EQ(k["corners_px"].size(), 4u);
            EXPECT_NEAR(k["diameter_px"].get<double>(), we, 0.5);
            EXPECT_EQ(k["strips"].get<int>(), 3);
            EXPECT_GT(canvas.layer().rect_count, 0u);
            if (tracker == &raw) {
                EXPECT_TRUE(k["tip_mm"].is_null());
                EXPECT_TRUE(k["depth_mm"].is_null());
                continue;
            }
            EXPECT_NEAR(k["depth_mm"].get<double>(), z, 0.015 * z);
            EXPECT_NEAR(k["tip_mm"][0].get<double>(), (xe - 320) * z / kFocal, 0.25);
            EXPECT_NEAR(k["tip_mm"][1].get<double>(), 0.0, 0.1);
            EXPECT_NEAR(k["tip_mm"][2].get<double>(), z, 0.015 * z);
        }
    }
}

}  // namespace
}  // namespace endotower::vision
