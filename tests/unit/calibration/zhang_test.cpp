// OpenCV's calibration (Zhang) on the real grids in ../shared/data, the automatic
// rejection of inconsistent views, ChArUco on rendered views, target parsing.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "calib_test_util.hpp"
#include "endotower/calibration/target.hpp"
#include "endotower/calibration/zhang_calibration.hpp"

namespace endotower::calibration::test {
namespace {

struct Detected {
    std::vector<View> views;
    int width = 0, height = 0;
};

// Detects `target` (with `spacing`) in the images of `dir` whose names start with
// `prefix`; cached, the detections are the slow part.
const Detected& detect_all(const std::string& dir, const std::string& prefix,
                           const std::string& target, const std::string& spacing) {
    static std::map<std::string, Detected> cache;
    const std::string key = dir + "|" + prefix + "|" + target + "|" + spacing;
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    Detected d;
    TargetSpec spec;
    std::string error;
    EXPECT_TRUE(parse_target(target, spacing, spec, error)) << error;
    std::vector<std::string> paths;
    EXPECT_TRUE(list_images(dir, paths, error)) << error;
    for (const std::string& p : paths) {
        if (std::filesystem::path(p).filename().string().rfind(prefix, 0) != 0) continue;
        GrayImage g;
        EXPECT_TRUE(load_gray_image(p, g, error)) << error;
        d.width = g.width, d.height = g.height;
        View v;
        EXPECT_TRUE(detect_target(g, spec, v, error)) << error;
        d.views.push_back(v);
    }
    return cache[key] = d;
}

#define SKIP_WITHOUT(dir)                    \
    if (!std::filesystem::is_directory(dir)) \
    GTEST_SKIP() << "no real data at " << (dir) << " (../shared/data absent)"

// OpenCV's sample chessboards: RMS <= 0.5 px, pinhole and fisheye. left02 is the view
// OpenCV's own left_intrinsics.yml lists at 1.18 px (the others about 0.2 px): it is
// the one the rejection drops (pinhole).
TEST(ZhangCalibration, OpenCvSampleChessboardsBelowHalfPixel) {
    const std::string dir = shared_data("opencv_samples");
    SKIP_WITHOUT(dir);
    const Detected& d = detect_all(dir, "left", "chessboard:9x6", "25");
    ASSERT_EQ(d.views.size(), 13u);
    ZhangResult r;
    std::string error;
    ASSERT_TRUE(calibrate_zhang(d.views, d.width, d.height, LensModel::kPinhole, r, error))
        << error;
    std::printf("pinhole: RMS %.4f px, fx %.2f fy %.2f cx %.2f cy %.2f, spacing error %.4f mm\n",
                r.rms, r.fx, r.fy, r.cx, r.cy, r.spacing_error);
    EXPECT_LE(r.rms, 0.5);
    ASSERT_EQ(r.dropped.size(), 1u);
    EXPECT_EQ(r.dropped[0].name, "left02.jpg");
    EXPECT_NE(r.dropped[0].reason.find("inconsistent"), std::string::npos);
    EXPECT_EQ(r.views.size(), 12u);
    // OpenCV's own figure for these views (fixed aspect ratio): fx 535.9 px.
    EXPECT_NEAR(r.fx, 535.9, 0.02 * 535.9);
    // 25 mm squares reconstructed on the board plane within 0.1 mm.
    EXPECT_LT(r.spacing_error, 0.1);
    // Fisheye on all 13 views (no rejection: below 0.5 px with left02 too).
    ASSERT_TRUE(calibrate_zhang(d.views, d.width, d.height, LensModel::kFisheye, r, error,
                                {.reject_inconsistent = false}))
        << error;
    std::printf("fisheye, 13 views: RMS %.4f px, fx %.2f fy %.2f\n", r.rms, r.fx, r.fy);
    EXPECT_LE(r.rms, 0.5);
    EXPECT_NEAR(r.fx, 535.9, 0.02 * 535.9);
}

// The endocal grid with the layout that matches its images (OpenCV's asymmetric
// layout: rows 1 unit apart, 2 units along a row) on the reference's ten frames and
// flags reproduces calibration_001-010.xml to its printed digits.
TEST(ZhangCalibration, EndocalReproducesTheReferenceCalibration) {
    const std::string dir = shared_data("endocal/sample_001");
    SKIP_WITHOUT(dir);
    const Detected& d = detect_all(dir, "frame", "asymmetric-circles:3x11", "2,1");
    ASSERT_EQ(d.views.size(), 11u);
    const std::vector<View> ten(d.views.begin(), d.views.begin() + 10);
    ZhangResult r;
    std::string error;
    ASSERT_TRUE(calibrate_zhang(ten, d.width, d.height, LensModel::kPinhole, r, error,
                                {.zero_tangent = true}))
        << error;
    EXPECT_TRUE(r.dropped.empty());
    EXPECT_NEAR(r.rms, 0.284, 0.001);
    EXPECT_NEAR(r.fx, 649.50, 0.01);
    EXPECT_NEAR(r.fy, 649.71, 0.01);
    EXPECT_NEAR(r.cx, 420.12, 0.01);
    EXPECT_NEAR(r.cy, 361.47, 0.01);
    ASSERT_EQ(r.distortion.size(), 5u);
    EXPECT_NEAR(r.distortion[0], -0.488, 0.001);
    EXPECT_NEAR(r.distortion[1], 0.347, 0.001);
    EXPECT_NEAR(r.distortion[4], -0.145, 0.001);
    // All eleven frames, default model: below 0.5 px, nothing to drop.
    ASSERT_TRUE(calibrate_zhang(d.views, d.width, d.height, LensModel::kPinhole, r, error))
        << error;
    std::printf("endocal, 11 frames: RMS %.4f px, fx %.2f fy %.2f\n", r.rms, r.fx, r.fy);
    EXPECT_LE(r.rms, 0.5);
    EXPECT_TRUE(r.dropped.empty());
}

// The layout "3 along a row, 1 between rows" (--spacing 3,1) does not fit these
// images: the fit needs fx ~ 10^4 px (RMS 1.06 px with frame_011, 0.44 without: the
// figures the issue quotes). Refused, naming the likely cause.
TEST(ZhangCalibration, EndocalWithTheThreeOneLayoutIsRefused) {
    const std::string dir = shared_data("endocal/sample_001");
    SKIP_WITHOUT(dir);
    const Detected& d = detect_all(dir, "frame", "asymmetric-circles:3x11", "3,1");
    ASSERT_EQ(d.views.size(), 11u);
    ZhangResult r;
    std::string error;
    EXPECT_FALSE(calibrate_zhang(d.views, d.width, d.height, LensModel::kPinhole, r, error,
                                 {.reject_inconsistent = false}));
    EXPECT_NE(error.find("implausible focal length"), std::string::npos) << error;
    EXPECT_NE(error.find("--spacing"), std::string::npos) << error;
}

// A detection that numbers the circles wrongly (rows 0 and 2 of frame_006 swapped,
// both unshifted rows, so each looks like a row) ruins the naive fit; the rejection
// finds that view, names it and why, and the result equals the clean ten-view fit.
TEST(ZhangCalibration, InconsistentDetectionIsDroppedAndNamed) {
    const std::string dir = shared_data("endocal/sample_001");
    SKIP_WITHOUT(dir);
    const Detected& d = detect_all(dir, "frame", "asymmetric-circles:3x11", "2,1");
    ASSERT_EQ(d.views.size(), 11u);
    std::vector<View> views = d.views;
    View& bad = views[5];
    ASSERT_EQ(bad.name, "frame_006.jpg");
    for (int c = 0; c < 3; ++c) std::swap(bad.image_points[c], bad.image_points[6 + c]);
    ZhangResult naive, r;
    std::string error;
    ASSERT_TRUE(calibrate_zhang(views, d.width, d.height, LensModel::kPinhole, naive, error,
                                {.reject_inconsistent = false}))
        << error;
    EXPECT_GT(naive.rms, 1.0);
    ASSERT_TRUE(calibrate_zhang(views, d.width, d.height, LensModel::kPinhole, r, error)) << error;
    ASSERT_EQ(r.dropped.size(), 1u);
    EXPECT_EQ(r.dropped[0].name, "frame_006.jpg");
    std::printf("dropped %s: %s\n", r.dropped[0].name.c_str(), r.dropped[0].reason.c_str());
    EXPECT_LE(r.rms, 0.5);
    std::vector<View> clean = d.views;
    clean.erase(clean.begin() + 5);
    ZhangResult ref;
    ASSERT_TRUE(calibrate_zhang(clean, d.width, d.height, LensModel::kPinhole, ref, error))
        << error;
    EXPECT_NEAR(r.rms, ref.rms, 1e-4);
    EXPECT_NEAR(r.fx, ref.fx, 0.01);
}

// ChArUco: the board drawn by OpenCV, seen by a known pinhole camera from eight poses
// (rendered by homography); the calibration recovers fx, fy, cx, cy within 1%.
TEST(ZhangCalibration, CharucoOnRenderedViews) {
    TargetSpec spec;
    std::string error;
    ASSERT_TRUE(parse_target("charuco:7x5:DICT_4X4_50", "20,15", spec, error)) << error;
    const auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
    const auto board = cv::aruco::CharucoBoard::create(7, 5, 20.f, 15.f, dict);
    cv::Mat art;
    const double px_per_mm = 5;  // board image: 140 x 100 mm at 5 px/mm, 10 mm margin
    board->draw(cv::Size(140 * 5 + 100, 100 * 5 + 100), art, 50, 1);
    const cv::Matx33d k(800, 0, 330, 0, 790, 245, 0, 0, 1);
    const double poses[8][6] = {{0.5, 0, 0, -70, -50, 320},      {-0.5, 0.1, 0.1, -70, -50, 330},
                                {0, 0.5, -0.1, -60, -50, 300},   {0.1, -0.5, 0.2, -80, -40, 340},
                                {0.4, 0.4, 0.3, -60, -60, 350},  {-0.4, -0.4, -0.2, -70, -50, 310},
                                {0.4, -0.4, 0.5, -70, -50, 330}, {-0.4, 0.4, -0.5, -70, -50, 330}};
    std::vector<View> views;
    for (int i = 0; i < 8; ++i) {
        cv::Matx33d rot;
        cv::Rodrigues(cv::Vec3d(poses[i][0], poses[i][1], poses[i][2]), rot);
        // Board mm -> camera; art pixel (u, v) -> board mm ((u - 50) / 5, (v - 50) / 5).
        const cv::Matx33d rt(rot(0, 0), rot(0, 1), poses[i][3], rot(1, 0), rot(1, 1), poses[i][4],
                             rot(2, 0), rot(2, 1), poses[i][5]);
        const cv::Matx33d art_to_mm(1 / px_per_mm, 0, -50 / px_per_mm, 0, 1 / px_per_mm,
                                    -50 / px_per_mm, 0, 0, 1);
        cv::Mat img;
        cv::warpPerspective(art, img, cv::Mat(k * rt * art_to_mm), cv::Size(640, 480),
                            cv::INTER_AREA, cv::BORDER_CONSTANT, 255);
        GrayImage g{640, 480, std::vector<std::uint8_t>(img.datastart, img.dataend),
                    "view" + std::to_string(i)};
        View v;
        ASSERT_TRUE(detect_target(g, spec, v, error)) << error;
        views.push_back(v);
    }
    ZhangResult r;
    ASSERT_TRUE(calibrate_zhang(views, 640, 480, LensModel::kPinhole, r, error)) << error;
    std::printf("charuco: RMS %.3f fx %.2f fy %.2f cx %.2f cy %.2f dropped %zu\n", r.rms, r.fx,
                r.fy, r.cx, r.cy, r.dropped.size());
    EXPECT_LE(r.rms, 0.5);
    EXPECT_NEAR(r.fx, 800, 8);
    EXPECT_NEAR(r.fy, 790, 7.9);
    EXPECT_NEAR(r.cx, 330, 6.4);
    EXPECT_NEAR(r.cy, 245, 4.8);
}

// A symmetric circle grid (circles:4x11, 10 mm), drawn and seen by a known pinhole
// camera from eight poses: fx, fy, cx, cy within 1.5%.
TEST(ZhangCalibration, SymmetricCirclesOnRenderedViews) {
    TargetSpec spec;
    std::string error;
    ASSERT_TRUE(parse_target("circles:4x11", "10", spec, error)) << error;
    const double px_per_mm = 5, margin_mm = 20;
    cv::Mat art(static_cast<int>((100 + 2 * margin_mm) * px_per_mm),
                static_cast<int>((30 + 2 * margin_mm) * px_per_mm), CV_8UC1, cv::Scalar(255));
    for (int r = 0; r < 11; ++r)
        for (int c = 0; c < 4; ++c)
            cv::circle(art,
                       cv::Point(cvRound((margin_mm + 10 * c) * px_per_mm * 16),
                                 cvRound((margin_mm + 10 * r) * px_per_mm * 16)),
                       cvRound(3 * px_per_mm * 16), cv::Scalar(0), cv::FILLED, cv::LINE_AA, 4);
    const cv::Matx33d k(800, 0, 330, 0, 790, 245, 0, 0, 1);
    const double poses[8][6] = {{0.5, 0, 0, -15, -50, 320},      {-0.5, 0.1, 0.1, -15, -50, 330},
                                {0, 0.5, -0.1, -15, -50, 300},   {0.1, -0.5, 0.2, -15, -50, 340},
                                {0.4, 0.4, 0.3, -15, -50, 350},  {-0.4, -0.4, -0.2, -15, -50, 310},
                                {0.4, -0.4, 0.5, -15, -50, 330}, {-0.4, 0.4, -0.5, -15, -50, 330}};
    std::vector<View> views;
    for (int i = 0; i < 8; ++i) {
        cv::Matx33d rot;
        cv::Rodrigues(cv::Vec3d(poses[i][0], poses[i][1], poses[i][2]), rot);
        const cv::Matx33d rt(rot(0, 0), rot(0, 1), poses[i][3], rot(1, 0), rot(1, 1), poses[i][4],
                             rot(2, 0), rot(2, 1), poses[i][5]);
        const cv::Matx33d art_to_mm(1 / px_per_mm, 0, -margin_mm, 0, 1 / px_per_mm, -margin_mm, 0,
                                    0, 1);
        cv::Mat img;
        cv::warpPerspective(art, img, cv::Mat(k * rt * art_to_mm), cv::Size(640, 480),
                            cv::INTER_LINEAR, cv::BORDER_CONSTANT, 255);
        GrayImage g{640, 480, std::vector<std::uint8_t>(img.datastart, img.dataend),
                    "circles" + std::to_string(i)};
        View v;
        ASSERT_TRUE(detect_target(g, spec, v, error)) << error;
        views.push_back(v);
    }
    ZhangResult r;
    ASSERT_TRUE(calibrate_zhang(views, 640, 480, LensModel::kPinhole, r, error)) << error;
    EXPECT_LE(r.rms, 0.5);
    EXPECT_NEAR(r.fx, 800, 12);
    EXPECT_NEAR(r.fy, 790, 12);
    EXPECT_NEAR(r.cx, 330, 9.6);
    EXPECT_NEAR(r.cy, 245, 7.2);
    EXPECT_LT(r.spacing_error, 0.1);
}

TEST(ZhangCalibration, TargetParsing) {
    TargetSpec t;
    std::string error;
    ASSERT_TRUE(parse_target("asymmetric-circles:3x11", "3,1", t, error)) << error;
    EXPECT_EQ(t.kind, TargetKind::kAsymmetricCircles);
    EXPECT_EQ(t.cols, 3);
    EXPECT_EQ(t.rows, 11);
    EXPECT_EQ(t.spacing_a, 3);
    EXPECT_EQ(t.spacing_b, 1);
    ASSERT_TRUE(parse_target("asymmetric-circles:4x11", "20", t, error)) << error;
    EXPECT_EQ(t.spacing_a, 40);  // OpenCV's layout: 2S along a row
    EXPECT_EQ(t.spacing_b, 20);
    ASSERT_TRUE(parse_target("circles:4x11", "", t, error)) << error;
    EXPECT_EQ(t.spacing_a, 1);
    for (const auto& [target, spacing, what] :
         std::vector<std::tuple<std::string, std::string, std::string>>{
             {"chessboard", "", "COLSxROWS"},
             {"chessboard:9x", "", "COLSxROWS"},
             {"chessboard:9x6x", "", "COLSxROWS"},
             {"chessboard:1x6", "", "COLSxROWS"},
             {"hexagons:9x6", "", "unknown kind"},
             {"chessboard:9x6", "-3", "positive"},
             {"chessboard:9x6", "3;1", "MM or A,B"},
             {"charuco:7x5", "20", "SQUARE,MARKER"},
             {"charuco:7x5", "20,25", "smaller"},
             {"charuco:7x5:DICT_9X9", "20,15", "dictionary"}}) {
        EXPECT_FALSE(parse_target(target, spacing, t, error)) << target << " " << spacing;
        EXPECT_NE(error.find(what), std::string::npos) << error;
    }
}

TEST(ZhangCalibration, TooFewViewsAndPoints) {
    View v{"a.png", {{1, 1}, {2, 2}}, {{0, 0, 0}, {1, 0, 0}}};
    ZhangResult r;
    std::string error;
    EXPECT_FALSE(calibrate_zhang({v, v, v}, 640, 480, LensModel::kPinhole, r, error));
    EXPECT_NE(error.find("a.png: too few points"), std::string::npos) << error;
    EXPECT_FALSE(calibrate_zhang({}, 640, 480, LensModel::kPinhole, r, error));
    EXPECT_NE(error.find("too few views"), std::string::npos) << error;
}

TEST(ZhangCalibration, GridNotFoundNamesTheImage) {
    GrayImage blank{320, 240, std::vector<std::uint8_t>(320 * 240, 200), "blank.png"};
    TargetSpec spec;
    std::string error;
    ASSERT_TRUE(parse_target("chessboard:9x6", "", spec, error));
    View v;
    EXPECT_FALSE(detect_target(blank, spec, v, error));
    EXPECT_NE(error.find("blank.png: grid not found (9x6 inner corners)"), std::string::npos)
        << error;
}

}  // namespace
}  // namespace endotower::calibration::test
