// The calibration file (format, validation, hash), the undistortion remap against
// the simulator's exact camera, and the per-frame field-of-view check.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "calib_test_util.hpp"
#include "endotower/app/json_line.hpp"
#include "endotower/app/overlay_canvas.hpp"
#include "endotower/calibration/calibration_file.hpp"
#include "endotower/calibration/calibration_stage.hpp"
#include "endotower/calibration/fov_monitor.hpp"
#include "endotower/calibration/square_grid.hpp"
#include "endotower/calibration/undistorter.hpp"

namespace endotower::calibration::test {
namespace {

Calibration sample() {
    Calibration c;
    c.scope = "olympus-wa53000a";
    c.model = LensModel::kPinhole;
    c.width = 768, c.height = 710;
    c.fx = 649.5, c.fy = 649.71, c.cx = 420.12, c.cy = 361.47;
    c.distortion = {-0.488, 0.347, 0, 0, -0.145};
    c.rms = 0.284;
    c.fov = {384, 355, 340};
    c.book = RadialPolynomial{{0.013084138, 0.000001575}, 384, 355};
    c.separation = SeparationTable{10, {60, 70, 80}, {58, 50, 40}};
    return c;
}

TEST(CalibrationFile, RoundTrip) {
    const Calibration c = sample();
    const std::string text = format_calibration(c);
    Calibration back;
    std::string error;
    ASSERT_TRUE(parse_calibration(text, "scope.json", back, error)) << error;
    EXPECT_EQ(back.scope, c.scope);
    EXPECT_EQ(back.model, c.model);
    EXPECT_EQ(back.width, 768);
    EXPECT_EQ(back.height, 710);
    EXPECT_DOUBLE_EQ(back.fx, c.fx);
    EXPECT_DOUBLE_EQ(back.cy, c.cy);
    EXPECT_EQ(back.distortion, c.distortion);
    EXPECT_DOUBLE_EQ(back.rms, c.rms);
    EXPECT_DOUBLE_EQ(back.fov.radius, 340);
    ASSERT_TRUE(back.book.has_value());
    EXPECT_EQ(back.book->k, c.book->k);
    ASSERT_TRUE(back.separation.has_value());
    EXPECT_EQ(back.separation->separation_px, c.separation->separation_px);
    // The names outside checks read are top-level members.
    for (const char* key : {"\"fx\"", "\"fy\"", "\"cx\"", "\"cy\"", "\"distortion\"", "\"rms\""})
        EXPECT_NE(text.find(std::string("\n  ") + key + ":"), std::string::npos) << key;
}

TEST(CalibrationFile, ValidationNamesTheProblem) {
    const std::string good = format_calibration(sample());
    auto with = [&](const std::string& from, const std::string& to) {
        std::string t = good;
        const auto at = t.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        return t.replace(at, from.size(), to);
    };
    const std::vector<std::pair<std::string, std::string>> cases = {
        {with("\"fx\": 649.5", "\"fx\": -1"), "scope.json: 'fx' must be a positive number"},
        {with("\"fx\": 649.5,", ""), "scope.json: missing field 'fx'"},
        {with("\"fy\": 649.71", "\"fy\": \"a\""), "'fy' must be a number"},
        {with("\"cx\": 420.12", "\"cx\": 900"), "the centre (cx, cy) lies outside the image"},
        {with("\"model\": \"pinhole\"", "\"model\": \"fisheye\""), "fisheye needs 4"},
        {with("\"model\": \"pinhole\"", "\"model\": \"zoom\""), "'model' is 'zoom'"},
        {with("\"scope\": \"olympus-wa53000a\"", "\"scope\": \"\""), "missing field 'scope'"},
        {with("\"rms\": 0.284", "\"rms\": -0.1"), "'rms' must not be negative"},
        {with("1.575e-06", "0.0001"), "'book_polynomial' is not monotonic"},
        {with("50.0,\n      40.0", "50.0,\n      52.0"), "separation must fall"},
        {with("\"fx\": 649.5,", "\"fx\": 649.5,,"), "scope.json:2: not valid JSON"},
        // Sizes and radii a parser would loop over or narrow (found by fuzz_calibration).
        {with("\"fx\": 649.5", "\"fx\": 1e999"),
         "scope.json: not valid JSON (a number out of range)"},
        {with("768,", "16385,"), "'image_size' must be [width, height], whole numbers 1..16384"},
        {with("768,", "18446744073709551615,"), "whole numbers 1..16384"},
        {with("768,", "-768,"), "whole numbers 1..16384"},
        {with("768,", "768.0,"), "whole numbers 1..16384"},
        {with("\"radius\": 340.0", "\"radius\": 1e300"),
         "'fov.radius' is larger than the image's diagonal (1045 px)"},
        {with("\"cx\": 384.0,\n    \"cy\": 355.0,\n    \"radius\"",
              "\"cx\": -5.0,\n    \"cy\": 355.0,\n    \"radius\""),
         "the 'fov' centre lies outside the image"},
        {with("\"cx\": 384.0,\n    \"cy\": 355.0,\n    \"k\"",
              "\"cx\": 384.0,\n    \"cy\": 1e9,\n    \"k\""),
         "the 'book_polynomial' centre lies outside the image"},
    };
    for (const auto& [text, what] : cases) {
        Calibration c;
        std::string error;
        EXPECT_FALSE(parse_calibration(text, "scope.json", c, error)) << what;
        EXPECT_NE(error.find(what), std::string::npos) << "got: " << error;
    }
    Calibration c;
    std::string error;
    EXPECT_FALSE(load_calibration("/nonexistent/scope.json", c, error));
    EXPECT_NE(error.find("/nonexistent/scope.json: cannot open"), std::string::npos) << error;
}

TEST(CalibrationFile, ContentHashIsFnv1a64) {
    EXPECT_EQ(content_hash(""), "cbf29ce484222325");
    EXPECT_EQ(content_hash("a"), "af63dc4c8601ec8c");
}

// The book model with the simulator's own distortion (r_d = r_u (1 + k1 r_u^2 +
// k2 r_u^4), i.e. dr = -k1 r^3 - k2 r^5): the map is the camera's distort()
// exactly, and the remapped chart's square centres land on the truth's undistorted
// points within 0.5 px (table 2.5's bound).
TEST(Undistorter, BookModelUndoesTheSimulatorsDistortion) {
    const char* chart = R"(
frames: 1
light: 0.9
target: {kind: squares, pitch_mm: 8, size_mm: 4, cols: 15, rows: 13, distances_mm: 45}
)";
    scene::SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(scenario_or_fail(chart), 5, error)) << error;
    const scene::CameraModel& cam = r.camera();
    Calibration c;
    c.scope = "sim";
    c.model = LensModel::kBook;
    c.width = cam.width, c.height = cam.height;
    c.fx = cam.fx, c.fy = cam.fy, c.cx = cam.cx, c.cy = cam.cy;
    c.distortion = {0, -cam.k[0], -cam.k[1]};
    c.book = RadialPolynomial{c.distortion, cam.cx, cam.cy};
    Undistorter u;
    ASSERT_TRUE(u.init(c, error)) << error;
    for (const auto& [x, y] :
         std::vector<std::pair<double, double>>{{10, 10}, {320, 240}, {600, 100}, {150, 420}}) {
        double xd, yd;
        cam.distort(x, y, xd, yd);
        const Point2 s = u.source_of(x, y);
        EXPECT_NEAR(s.x, xd, 1e-6);
        EXPECT_NEAR(s.y, yd, 1e-6);
    }
    scene::Image img;
    scene::FrameTruth truth;
    r.render(0, img, truth);
    std::vector<std::uint8_t> out(img.bgr.size());
    hal::Frame in_f, out_f;
    in_f.format = out_f.format = {img.width, img.height, img.width * 3, hal::PixelFormat::kBgr24};
    in_f.data = img.bgr.data();
    out_f.data = out.data();
    ASSERT_TRUE(u.apply(in_f, out_f));
    GrayImage g;
    ASSERT_TRUE(gray_from_frame(out_f, g));
    // The corrected image's field of view is larger than the displayed circle.
    const FovCircle whole{cam.cx, cam.cy, 2.0 * cam.height};
    std::vector<Point2> centres;
    ASSERT_TRUE(detect_square_centres(g, whole, centres, error)) << error;
    int matched = 0;
    for (const Point2& p : centres) {
        double best = 1e9;
        for (const scene::Px& t : truth.target.points_px_u)
            best = std::min(best, std::hypot(t.x - p.x, t.y - p.y));
        // Squares cut by the corrected image's edge or the circle have biased centroids.
        double xd, yd;
        cam.distort(p.x, p.y, xd, yd);
        if (std::hypot(xd - cam.fov_cx, yd - cam.fov_cy) > cam.fov_radius - 25) continue;
        if (p.x < 40 || p.y < 40 || p.x > cam.width - 40 || p.y > cam.height - 40) continue;
        EXPECT_LT(best, 0.5) << "square at " << p.x << ", " << p.y;
        ++matched;
    }
    EXPECT_GE(matched, 20);
}

// The remap samples bilinearly at the map's source (fixed point: within 2 levels on
// a smooth ramp, every channel; gray, BGR and BGRA take different code paths), and
// pixels whose source is outside the field of view are black.
TEST(Undistorter, PinholeRemapMatchesTheExactMap) {
    Calibration c = sample();
    c.model = LensModel::kPinhole;
    Undistorter u;
    std::string error;
    ASSERT_TRUE(u.init(c, error)) << error;
    for (const auto& [fmt, channels] :
         std::vector<std::pair<hal::PixelFormat, int>>{{hal::PixelFormat::kGray8, 1},
                                                       {hal::PixelFormat::kBgr24, 3},
                                                       {hal::PixelFormat::kBgra32, 4}}) {
        const int stride = c.width * channels + 8;  // padded rows
        std::vector<std::uint8_t> in(static_cast<std::size_t>(stride) * c.height),
            out(in.size(), 77);
        auto level = [](double x, double y, int ch) { return (x + y) / 8.0 + 15 * ch; };
        for (int y = 0; y < c.height; ++y)
            for (int x = 0; x < c.width; ++x)
                for (int ch = 0; ch < channels; ++ch)
                    in[y * stride + x * channels + ch] = static_cast<std::uint8_t>(level(x, y, ch));
        hal::Frame fi, fo;
        fi.format = fo.format = {c.width, c.height, stride, fmt};
        fi.data = in.data();
        fo.data = out.data();
        ASSERT_TRUE(u.apply(fi, fo));
        int checked = 0, black = 0;
        for (int y = 0; y < c.height; y += 7)
            for (int x = 0; x < c.width; x += 5) {
                const Point2 s = u.source_of(x, y);
                for (int ch = 0; ch < channels; ++ch) {
                    const int got = out[y * stride + x * channels + ch];
                    if (!c.fov.contains(s.x, s.y)) {
                        EXPECT_EQ(got, 0) << x << ", " << y;
                        black += ch == 0;
                        continue;
                    }
                    if (s.x < 1 || s.y < 1 || s.x > c.width - 2 || s.y > c.height - 2) continue;
                    EXPECT_NEAR(got, level(s.x, s.y, ch), 2.0)
                        << x << ", " << y << " channel " << ch;
                    checked += ch == 0;
                }
            }
        EXPECT_GT(checked, 1000) << channels;
        EXPECT_GT(black, 100) << channels;
    }
    hal::Frame a, b;
    std::vector<std::uint8_t> buf(c.width * c.height * 3);
    a.format = b.format = {c.width, c.height, c.width * 3, hal::PixelFormat::kBgr24};
    a.data = b.data = buf.data();
    b.format.width = 100;
    EXPECT_FALSE(u.apply(a, b));
}

// The helper thread remaps half the rows: the output is the one-thread output, byte
// for byte (every pixel, the black border included), frame after frame, with the
// thread switched on and off again and the maps rebuilt under it.
TEST(Undistorter, TwoThreadsGiveTheSameBytes) {
    Calibration c = sample();
    c.model = LensModel::kPinhole;
    Undistorter one, two;
    std::string error;
    ASSERT_TRUE(one.init(c, error)) << error;
    ASSERT_TRUE(two.init(c, error)) << error;
    EXPECT_FALSE(two.set_threads(3));
    ASSERT_TRUE(two.set_threads(2));
    EXPECT_EQ(two.threads(), 2);
    const int stride = c.width * 3;
    std::vector<std::uint8_t> in(static_cast<std::size_t>(stride) * c.height), a(in.size(), 1),
        b(in.size(), 2);
    hal::Frame fi, fa, fb;
    fi.format = fa.format = fb.format = {c.width, c.height, stride, hal::PixelFormat::kBgr24};
    fi.data = in.data();
    fa.data = a.data();
    fb.data = b.data();
    for (int frame = 0; frame < 6; ++frame) {
        for (std::size_t i = 0; i < in.size(); ++i)
            in[i] = static_cast<std::uint8_t>((i * 7 + frame * 31) ^ (i >> 9));
        if (frame == 3) {
            ASSERT_TRUE(two.init(c, error)) << error;  // keeps its thread
        }
        ASSERT_TRUE(one.apply(fi, fa));
        ASSERT_TRUE(two.apply(fi, fb));
        ASSERT_EQ(two.threads(), 2);
        ASSERT_TRUE(a == b) << "frame " << frame;
    }
    ASSERT_TRUE(two.set_threads(1));
    EXPECT_EQ(two.threads(), 1);
    std::fill(b.begin(), b.end(), 9);
    ASSERT_TRUE(two.apply(fi, fb));
    EXPECT_TRUE(a == b);
}

// Every pixel loop this CPU runs (scalar, SSE2, AVX2) gives the same bytes, for every
// pixel format, padded rows, random content (the SIMD paths claim bit-exact arithmetic).
TEST(Undistorter, KernelsGiveTheSameBytes) {
    for (const LensModel model : {LensModel::kPinhole, LensModel::kBook}) {
        Calibration c = sample();
        c.model = model;
        Undistorter u;
        std::string error;
        ASSERT_TRUE(u.init(c, error)) << error;
        EXPECT_NE(u.kernel(), Undistorter::Kernel::kBest);
        for (const auto& [fmt, channels] :
             std::vector<std::pair<hal::PixelFormat, int>>{{hal::PixelFormat::kGray8, 1},
                                                           {hal::PixelFormat::kBgr24, 3},
                                                           {hal::PixelFormat::kBgra32, 4}}) {
            const int stride = c.width * channels + 12;
            std::vector<std::uint8_t> in(static_cast<std::size_t>(stride) * c.height);
            std::uint32_t state = 12345;
            for (auto& b : in) {
                state = state * 1664525u + 1013904223u;
                b = static_cast<std::uint8_t>(state >> 24);
            }
            hal::Frame fi;
            fi.format = {c.width, c.height, stride, fmt};
            fi.data = in.data();
            std::vector<std::uint8_t> reference;
            int kernels = 0;
            for (const auto k : {Undistorter::Kernel::kScalar, Undistorter::Kernel::kSse2,
                                 Undistorter::Kernel::kAvx2}) {
                if (!u.set_kernel(k)) continue;
                ++kernels;
                std::vector<std::uint8_t> out(in.size(), static_cast<std::uint8_t>(kernels));
                hal::Frame fo = fi;
                fo.data = out.data();
                ASSERT_TRUE(u.apply(fi, fo));
                // Padding bytes are not pixels: compare the rows' pixel bytes only.
                for (int y = 0; y < c.height; ++y)
                    std::fill(out.begin() + y * stride + c.width * channels,
                              out.begin() + (y + 1) * stride, 0);
                if (reference.empty())
                    reference = out;
                else
                    ASSERT_TRUE(out == reference)
                        << "kernel " << static_cast<int>(k) << ", channels " << channels;
            }
            EXPECT_GE(kernels, 1);
        }
    }
}

// The stored map is sampled every 8th pixel and interpolated; where that would be off
// by more than 0.05 px anywhere in the field of view, a finer step is taken. Against
// the exact map: within 0.05 px (1/64 px of it is the fixed-point rounding), and every
// pixel whose source is in the field of view and the frame is remapped, for the
// strongly distorted pinhole lens of the sample, its book model, a mild and a strong
// fisheye.
TEST(Undistorter, InterpolatedMapStaysOnTheExactMap) {
    struct Case {
        LensModel model;
        std::vector<double> distortion;
        int node_step;
    };
    const Calibration base = sample();
    for (const Case& k :
         {Case{LensModel::kPinhole, base.distortion, 8}, Case{LensModel::kBook, base.distortion, 8},
          Case{LensModel::kFisheye, {0.01, -0.005, 0.001, 0}, 8},
          Case{LensModel::kFisheye, {0.05, -0.02, 0.01, 0}, 0}}) {
        Calibration c = base;
        c.model = k.model;
        c.distortion = k.distortion;
        Undistorter u;
        std::string error;
        ASSERT_TRUE(u.init(c, error)) << error;
        const Undistorter::MapStats s = u.map_stats();
        const int model = static_cast<int>(k.model);
        if (k.node_step) {
            EXPECT_EQ(s.node_step, k.node_step) << model;
        }
        EXPECT_LE(s.max_error_px, 0.05) << model;
        EXPECT_GE(s.max_error_px, 1.0 / 128) << model;  // the rounding shows
        // Every pixel whose exact source has its taps in the frame and lies in the field
        // of view is remapped (counted on the exact map, with a margin of one pixel for
        // sources that round across the frame's edge).
        // (The exact map from OpenCV directly: source_of per pixel is slow for these.)
        cv::Mat mx, my;
        const cv::Mat kk = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
        if (k.model == LensModel::kPinhole)
            cv::initUndistortRectifyMap(kk, cv::Mat(c.distortion), cv::Mat(), kk,
                                        {c.width, c.height}, CV_32FC1, mx, my);
        if (k.model == LensModel::kFisheye)
            cv::fisheye::initUndistortRectifyMap(kk, cv::Mat(c.distortion),
                                                 cv::Mat::eye(3, 3, CV_64F), kk,
                                                 {c.width, c.height}, CV_32FC1, mx, my);
        std::size_t inside = 0, edge = 0;
        for (int y = 0; y < c.height; ++y)
            for (int x = 0; x < c.width; ++x) {
                const Point2 p =
                    mx.empty() ? u.source_of(x, y) : Point2{mx.at<float>(y, x), my.at<float>(y, x)};
                if (!c.fov.contains(p.x, p.y)) continue;
                if (p.x >= 1 && p.y >= 1 && p.x <= c.width - 3 && p.y <= c.height - 3)
                    ++inside;
                else if (p.x > -1 && p.y > -1 && p.x < c.width - 1 && p.y < c.height - 1)
                    ++edge;
            }
        EXPECT_GE(s.remapped, inside) << model;
        EXPECT_LE(s.remapped, inside + edge) << model;
    }
}

// source_of writes OpenCV's lens models out (no allocation per call): it agrees with
// cv::projectPoints / cv::fisheye::projectPoints for 4, 5, 8 and 12 coefficients and
// the fisheye model, across the frame.
TEST(Undistorter, SourceOfMatchesOpenCvProjection) {
    struct Case {
        LensModel model;
        std::vector<double> d;
    };
    for (const Case& k :
         {Case{LensModel::kPinhole, {-0.3, 0.1, 0.001, -0.002}},
          Case{LensModel::kPinhole, {-0.488, 0.347, 0, 0, -0.145}},
          Case{LensModel::kPinhole, {-0.4, 0.2, 0.001, 0.002, -0.05, 0.01, 0.02, -0.01}},
          Case{LensModel::kPinhole,
               {-0.4, 0.2, 0.001, 0.002, -0.05, 0.01, 0.02, -0.01, 1e-3, -2e-3, 3e-3, 1e-3}},
          Case{LensModel::kFisheye, {0.05, -0.02, 0.01, -0.003}}}) {
        Calibration c = sample();
        c.model = k.model;
        c.distortion = k.d;
        Undistorter u;
        std::string error;
        ASSERT_TRUE(u.init(c, error)) << error;
        const cv::Mat kk = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
        const cv::Mat zero = cv::Mat::zeros(3, 1, CV_64F);
        for (int y = 0; y < c.height; y += 71)
            for (int x = 0; x < c.width; x += 64) {
                std::vector<cv::Point3d> ray{{(x - c.cx) / c.fx, (y - c.cy) / c.fy, 1.0}};
                std::vector<cv::Point2d> px;
                if (k.model == LensModel::kFisheye)
                    cv::fisheye::projectPoints(ray, px, zero, zero, kk, cv::Mat(k.d));
                else
                    cv::projectPoints(ray, zero, zero, kk, cv::Mat(k.d), px);
                const Point2 s = u.source_of(x, y);
                EXPECT_NEAR(s.x, px[0].x, 1e-6) << x << ", " << y << ", " << k.d.size();
                EXPECT_NEAR(s.y, px[0].y, 1e-6) << x << ", " << y << ", " << k.d.size();
            }
    }
}

TEST(Undistorter, FoldingBookPolynomialIsRefused) {
    Calibration c = sample();
    c.model = LensModel::kBook;
    c.book = RadialPolynomial{{0, 1e-4}, 384, 355};
    Undistorter u;
    std::string error;
    EXPECT_FALSE(u.init(c, error));
    EXPECT_NE(error.find("folds"), std::string::npos) << error;
}

// The per-frame check on white-background frames: unchanged -> ok; the image moved
// by 6 px -> shifted (by 6 px); magnified 10% or shrunk 15% -> scope changed;
// black -> unknown.
TEST(FovMonitor, FlagsShiftAndScopeChange) {
    const char* white = R"(
frames: 1
light: 0.7
target: {kind: white, distances_mm: 40}
)";
    scene::Scenario sc = scenario_or_fail(white);
    sc.width = 1280, sc.height = 720;
    scene::SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(sc, 7, error)) << error;
    scene::Image img;
    scene::FrameTruth truth;
    r.render(0, img, truth);
    const cv::Mat frame(img.height, img.width, CV_8UC3, img.bgr.data());
    GrayImage g;
    hal::Frame f;
    f.format = {img.width, img.height, img.width * 3, hal::PixelFormat::kBgr24};
    f.data = img.bgr.data();
    ASSERT_TRUE(gray_from_frame(f, g));
    FovCircle ref;
    ASSERT_TRUE(detect_fov_circle(g, ref, error)) << error;
    FovMonitor monitor(ref);
    FovCheck check = monitor.check(f);
    EXPECT_EQ(check.status, FovStatus::kOk);
    EXPECT_LT(check.shift_px, 0.5);
    EXPECT_GE(check.rays, 60);
    auto transformed = [&](const cv::Matx23d& m) {
        cv::Mat moved;
        cv::warpAffine(frame, moved, m, frame.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                       cv::Scalar::all(0));
        hal::Frame mf = f;
        mf.data = moved.data;
        return monitor.check(mf);
    };
    check = transformed(cv::Matx23d(1, 0, 6, 0, 1, 0));
    EXPECT_EQ(check.status, FovStatus::kShifted);
    EXPECT_NEAR(check.shift_px, 6.0, 0.5);
    for (const double s : {1.1, 0.85}) {
        check = transformed(cv::Matx23d(s, 0, (1 - s) * ref.cx, 0, s, (1 - s) * ref.cy));
        EXPECT_EQ(check.status, FovStatus::kScopeChanged) << s << " rays " << check.rays;
        EXPECT_NEAR(check.circle.radius, s * ref.radius, 1.0) << s;
    }
    std::vector<std::uint8_t> black(img.bgr.size(), 0);
    hal::Frame bf = f;
    bf.data = black.data();
    EXPECT_EQ(monitor.check(bf).status, FovStatus::kUnknown);
}

// mask_outside: every pixel whose centre is outside the circle is black in the frame's
// own format, every pixel inside is untouched (BGR, grey, YUYV in whole pairs, NV12
// with its chroma plane).
TEST(FovMask, BlackensExactlyTheOutside) {
    const FovCircle c{61.3, 40.7, 33.2};
    const int w = 128, h = 90;
    auto inside = [&](int x, int y) {
        return std::hypot(x + 0.5 - c.cx, y + 0.5 - c.cy) < c.radius;
    };
    for (const hal::PixelFormat pf :
         {hal::PixelFormat::kBgr24, hal::PixelFormat::kGray8, hal::PixelFormat::kBgra32}) {
        const int bpp = hal::bytes_per_pixel(pf), stride = w * bpp + 16;
        std::vector<std::uint8_t> px(static_cast<std::size_t>(stride) * h, 200);
        hal::Frame f;
        f.format = {w, h, stride, pf};
        f.data = px.data();
        mask_outside(f, c);
        int in = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int b = 0; b < bpp; ++b) {
                    ASSERT_EQ(px[y * stride + x * bpp + b], inside(x, y) ? 200 : 0)
                        << x << "," << y;
                    in += inside(x, y) && b == 0;
                }
        EXPECT_NEAR(in, M_PI * c.radius * c.radius, 0.03 * M_PI * c.radius * c.radius);
        for (int y = 0; y < h; ++y)
            EXPECT_EQ(px[y * stride + w * bpp], 200) << "row padding untouched";
    }
    {
        std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * 2 * h, 200);
        hal::Frame f;
        f.format = {w, h, w * 2, hal::PixelFormat::kYuyv};
        f.data = px.data();
        mask_outside(f, c);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; x += 2) {
                const bool keep = inside(x, y) || inside(x + 1, y);
                const std::uint8_t* p = &px[y * w * 2 + x * 2];
                if (keep) {
                    EXPECT_EQ(p[0], 200);
                } else {
                    EXPECT_EQ(p[0], 16) << x << "," << y;
                    EXPECT_EQ(p[1], 128);
                    EXPECT_EQ(p[2], 16);
                    EXPECT_EQ(p[3], 128);
                }
            }
    }
    {
        std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3 / 2, 200);
        hal::Frame f;
        f.format = {w, h, w, hal::PixelFormat::kNv12};
        f.data = px.data();
        mask_outside(f, c);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) ASSERT_EQ(px[y * w + x], inside(x, y) ? 200 : 16);
        const std::uint8_t* uv = px.data() + w * h;
        EXPECT_EQ(uv[0], 128);                                      // a corner
        EXPECT_EQ(uv[(20 / 2) * w + 2 * (60 / 2)], 200);            // near the centre
        EXPECT_EQ(uv[(h / 2 - 1) * w + 2 * (w / 2 - 1) + 1], 128);  // the far corner's V
    }
    std::vector<std::uint8_t> px(16, 7);
    hal::Frame f;
    f.format = {4, 4, 4, hal::PixelFormat::kGray8};
    f.data = px.data();
    mask_outside(f, FovCircle{});  // no circle: nothing happens
    EXPECT_EQ(px, std::vector<std::uint8_t>(16, 7));
}

// The stage masks the analysis frame for the stages after it: on a white-background
// frame the measured circle is used and the outside is black; on a black frame
// (no rim to measure) the calibrated circle; without set_mask nothing changes.
TEST(CalibrationStage, MasksOutsideTheFieldOfView) {
    scene::Scenario sc =
        scenario_or_fail("frames: 1\nlight: 0.7\ntarget: {kind: white, distances_mm: 40}\n");
    scene::SceneRenderer r;
    std::string error;
    ASSERT_TRUE(r.init(sc, 7, error)) << error;
    scene::Image img;
    scene::FrameTruth truth;
    r.render(0, img, truth);
    hal::Frame f;
    f.format = {img.width, img.height, img.width * 3, hal::PixelFormat::kBgr24};
    f.data = img.bgr.data();
    GrayImage g;
    ASSERT_TRUE(gray_from_frame(f, g));
    Calibration c = sample();
    c.width = img.width, c.height = img.height;
    ASSERT_TRUE(detect_fov_circle(g, c.fov, error)) << error;
    app::OverlayCanvas canvas;
    app::JsonLine line;
    auto run = [&](CalibrationStage& stage, hal::Frame& frame) {
        line.clear();
        line.begin_object();
        app::AnalysisContext ctx{frame, {}, canvas, line, 0};
        stage.process(ctx);
        line.end_object();
        return std::string(line.view());
    };
    CalibrationStage plain(c, "scope.json", "abc");
    plain.configure(f.format);
    const std::vector<std::uint8_t> before = img.bgr;
    const std::string t0 = run(plain, f);
    EXPECT_EQ(img.bgr, before);
    EXPECT_EQ(t0.find("fov_mask"), std::string::npos) << t0;
    CalibrationStage masking(c, "scope.json", "abc");
    masking.set_mask(true);
    masking.configure(f.format);
    const std::string t1 = run(masking, f);
    EXPECT_NE(t1.find("\"fov\":\"ok\""), std::string::npos) << t1;
    EXPECT_NE(t1.find("\"fov_mask\":\"measured\""), std::string::npos) << t1;
    int outside = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const std::size_t i = (static_cast<std::size_t>(y) * img.width + x) * 3;
            const double d = std::hypot(x + 0.5 - c.fov.cx, y + 0.5 - c.fov.cy);
            if (d > c.fov.radius + 3) {
                ASSERT_EQ(img.bgr[i] | img.bgr[i + 1] | img.bgr[i + 2], 0) << x << "," << y;
                ++outside;
            } else if (d < c.fov.radius - 3) {
                ASSERT_EQ(img.bgr[i], before[i]) << x << "," << y;
            }
        }
    EXPECT_GT(outside, 1000);
    std::vector<std::uint8_t> black(img.bgr.size(), 0);
    hal::Frame bf = f;
    bf.data = black.data();
    const std::string t2 = run(masking, bf);
    EXPECT_NE(t2.find("\"fov\":\"unknown\",\"fov_mask\":\"calibrated\""), std::string::npos) << t2;
}

// On the real endoscopic frame (tissue up to the rim): the check agrees with the
// full detection within 1 px.
TEST(FovMonitor, RealFrameAgreesWithTheDetection) {
    const std::string path = shared_data("endoseg_fov/demo.jpg");
    if (!std::filesystem::exists(path))
        GTEST_SKIP() << "no real data at " << path << " (../shared/data absent)";
    GrayImage g;
    std::string error;
    ASSERT_TRUE(load_gray_image(path, g, error)) << error;
    FovCircle ref;
    ASSERT_TRUE(detect_fov_circle(g, ref, error)) << error;
    hal::Frame f;
    f.format = {g.width, g.height, g.width, hal::PixelFormat::kGray8};
    f.data = g.pixels.data();
    const FovCheck check = FovMonitor(ref).check(f);
    EXPECT_EQ(check.status, FovStatus::kOk);
    EXPECT_LT(check.shift_px, 1.0);
    EXPECT_NEAR(check.circle.radius, ref.radius, 1.5);
}

}  // namespace
}  // namespace endotower::calibration::test
