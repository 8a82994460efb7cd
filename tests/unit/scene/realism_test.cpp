// Realism: simulator frames against real laparoscopy (../shared/data/sznitman_lap).
// Prints the numbers docs/scenario.md quotes; asserts only the ordering that says the
// simulator looks like laparoscopy: its colour distribution is closer to the real
// frames' than that of a non-surgical control picture (OpenCV's Graffiti).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "endotower/scene/renderer.hpp"
#include "endotower/scene/scenario.hpp"
#include "scene_test_util.hpp"

namespace endotower::scene::test {
namespace {

namespace fs = std::filesystem;

struct Stats {
    cv::Mat hist;  // hue x saturation, over lit pixels
    double edges = 0, contrast = 0;
    int images = 0, contrast_n = 0;
};

// Lit pixels: value >= 40 (leaves out the dark surround and black borders).
void add_image(Stats& s, const cv::Mat& bgr) {
    cv::Mat hsv, lit, gray, edges;
    cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
    cv::inRange(hsv, cv::Scalar(0, 0, 40), cv::Scalar(180, 255, 255), lit);
    cv::erode(lit, lit, cv::Mat(), cv::Point(-1, -1), 3);
    const int channels[] = {0, 1}, sizes[] = {30, 32};
    const float hr[] = {0, 180}, sr[] = {0, 256};
    const float* ranges[] = {hr, sr};
    cv::Mat h;
    cv::calcHist(&hsv, 1, channels, lit, h, 2, sizes, ranges);
    cv::normalize(h, h, 1, 0, cv::NORM_L1);
    if (s.hist.empty())
        s.hist = h;
    else
        s.hist += h;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    cv::Canny(gray, edges, 50, 150);
    s.edges +=
        static_cast<double>(cv::countNonZero(edges & lit)) / std::max(1, cv::countNonZero(lit));
    ++s.images;
}

// Michelson contrast of the shaft against the tissue beside it: pixels 8..40 px from
// the head along the shaft, and the same offset sideways by `side` px.
void add_contrast(Stats& s, const cv::Mat& bgr, double hx, double hy, double ang, double side) {
    cv::Mat gray;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    const double ux = std::cos(ang), uy = std::sin(ang);
    double tool = 0, bg = 0;
    int nt = 0, nb = 0;
    for (double a = 8; a <= 40; a += 2) {
        const cv::Point p(cvRound(hx + a * ux), cvRound(hy + a * uy));
        if (p.inside(cv::Rect(0, 0, gray.cols, gray.rows))) tool += gray.at<std::uint8_t>(p), ++nt;
        for (double sgn : {-1.0, 1.0}) {
            const cv::Point q(cvRound(p.x - sgn * side * uy), cvRound(p.y + sgn * side * ux));
            if (q.inside(cv::Rect(0, 0, gray.cols, gray.rows)) && gray.at<std::uint8_t>(q) >= 40)
                bg += gray.at<std::uint8_t>(q), ++nb;
        }
    }
    if (nt == 0 || nb == 0) return;
    tool /= nt, bg /= nb;
    s.contrast += std::abs(bg - tool) / (bg + tool);
    ++s.contrast_n;
}

double bhattacharyya(const Stats& a, const Stats& b) {
    cv::Mat x, y;
    cv::normalize(a.hist, x, 1, 0, cv::NORM_L1);
    cv::normalize(b.hist, y, 1, 0, cv::NORM_L1);
    return cv::compareHist(x, y, cv::HISTCMP_BHATTACHARYYA);
}

TEST(SceneRealism, CloserToRealLaparoscopyThanAControlPicture) {
    const fs::path real_dir = fs::path(ENDOTOWER_SHARED_DATA) / "sznitman_lap";
    if (!fs::is_directory(real_dir))
        GTEST_SKIP() << "no real data at " << real_dir << " (../shared/data absent)";
    // Real: every 20th frame, with its annotated head and shaft angle.
    Stats real;
    std::ifstream xml(real_dir / "train.xml");
    std::string tok;
    int index = -1, seen = 0;
    while (xml >> tok) {
        if (tok == "<PositionIndex>") xml >> index;
        if (tok != "<tool>" || index < 0) continue;
        double row, col, scale, angle;
        xml >> row >> col >> scale >> angle;
        if (index % 20 != 0 || index == seen) continue;
        seen = index;
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", index);
        const cv::Mat img = cv::imread((real_dir / "frames" / name).string());
        if (img.empty()) continue;
        add_image(real, img);
        add_contrast(real, img, col, row, angle, 0.6 * scale);
    }
    ASSERT_GE(real.images, 15);

    // Simulated: the table 4.1 nominal scenario, every 5th frame.
    Scenario sc;
    std::string error;
    const std::string path =
        std::string(ENDOTOWER_SOURCE_DIR) + "/board/sim/scenarios/t41_speed_0_4.yaml";
    ASSERT_TRUE(load_scenario(path, sc, error)) << error;
    SceneRenderer r;
    ASSERT_TRUE(r.init(sc, sc.seed, error)) << error;
    Stats sim;
    for (int f = 0; f < sc.frames; f += 5) {
        const Rendered out = render_frame(r, f);
        add_image(sim, out.image);
        const ToolTruth& t = out.truth.tools[0];
        add_contrast(sim, out.image, t.head_px.x, t.head_px.y, t.axis_deg * M_PI / 180,
                     1.2 * t.width_px);
    }

    Stats control;
    for (const char* name : {"graf1.png", "graf3.png"}) {
        const cv::Mat img =
            cv::imread((fs::path(ENDOTOWER_SHARED_DATA) / "opencv_samples" / name).string());
        ASSERT_FALSE(img.empty()) << name;
        add_image(control, img);
    }
    const double d_sim = bhattacharyya(sim, real), d_control = bhattacharyya(control, real);
    std::printf("| measure | simulator (%s) | real (sznitman_lap) |\n|---|---|---|\n",
                sc.name.c_str());
    std::printf(
        "| hue/saturation Bhattacharyya distance to real | %.3f | 0 (control picture: %.3f) |\n",
        d_sim, d_control);
    std::printf("| Canny edge density (lit pixels) | %.3f | %.3f |\n", sim.edges / sim.images,
                real.edges / real.images);
    std::printf("| shaft/tissue Michelson contrast | %.3f | %.3f |\n",
                sim.contrast / std::max(1, sim.contrast_n),
                real.contrast / std::max(1, real.contrast_n));
    EXPECT_LT(d_sim, d_control);
}

}  // namespace
}  // namespace endotower::scene::test
