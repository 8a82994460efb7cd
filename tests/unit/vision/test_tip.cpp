// Tip extraction along the midline with the book's three filters (fig. 4.19-4.21).
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "endotower/vision/tip_extractor.hpp"

namespace endotower::vision {
namespace {

struct Scene {
    cv::Mat img;
    EdgePair edges;
    Point2 toward_tip;
};

// Tissue (pink) with a dark shaft from `from` to the tip `to`, `width` px wide, and
// its edges given exactly (as the tracker would measure them) up to `edge_len` px
// before the tip.
Scene shaft(Point2 from, Point2 to, double width, double edge_gap = 15.0) {
    Scene s;
    s.img = cv::Mat(480, 640, CV_8UC3, cv::Scalar(120, 110, 200));
    const double dx = to.x - from.x, dy = to.y - from.y, L = std::hypot(dx, dy);
    const double ux = dx / L, uy = dy / L, nx = -uy * width / 2, ny = ux * width / 2;
    const cv::Point pts[4] = {cv::Point(cvRound(from.x + nx), cvRound(from.y + ny)),
                              cv::Point(cvRound(to.x + nx), cvRound(to.y + ny)),
                              cv::Point(cvRound(to.x - nx), cvRound(to.y - ny)),
                              cv::Point(cvRound(from.x - nx), cvRound(from.y - ny))};
    cv::fillConvexPoly(s.img, pts, 4, cv::Scalar(45, 45, 50));
    const Point2 end{to.x - ux * edge_gap, to.y - uy * edge_gap};
    s.edges.found = true;
    s.edges.e1 = {{from.x + nx, from.y + ny}, {end.x + nx, end.y + ny}};
    s.edges.e2 = {{from.x - nx, from.y - ny}, {end.x - nx, end.y - ny}};
    s.edges.midline = {from, end};
    s.toward_tip = {ux, uy};
    return s;
}

hal::Frame view(cv::Mat& m) {
    hal::Frame f;
    f.format = {m.cols, m.rows, static_cast<int>(m.step), hal::PixelFormat::kBgr24};
    f.data = m.data;
    return f;
}

TEST(TipExtractor, FindsTheTipOfAShallowTool) {
    Scene s = shaft({0, 100}, {350, 260}, 28);
    const TipResult r = extract_tip(view(s.img), s.edges, s.toward_tip, {});
    ASSERT_TRUE(r.found);
    EXPECT_FALSE(r.searched_in_y);
    EXPECT_NEAR(r.tip.x, 350, 2.0);
    EXPECT_NEAR(r.tip.y, 260, 2.0);
}

TEST(TipExtractor, AVerticalToolIsSearchedInY) {
    Scene s = shaft({300, 0}, {300, 310}, 30);
    const TipResult r = extract_tip(view(s.img), s.edges, s.toward_tip, {});
    ASSERT_TRUE(r.found);
    EXPECT_TRUE(r.searched_in_y);
    EXPECT_NEAR(r.tip.x, 300, 1.0);
    EXPECT_NEAR(r.tip.y, 310, 2.0);
}

TEST(TipExtractor, ASpecularGlintOnTheShaftIsNotTheTip) {
    Scene s = shaft({0, 240}, {420, 240}, 30, 60.0);
    // A saturated reflection on the shaft between the edges' end and the tip.
    cv::circle(s.img, cv::Point(380, 240), 8, cv::Scalar(255, 255, 255), cv::FILLED);
    const TipResult r = extract_tip(view(s.img), s.edges, s.toward_tip, {});
    ASSERT_TRUE(r.found);
    EXPECT_NEAR(r.tip.x, 420, 2.0);
}

TEST(TipExtractor, TheFieldOfViewRimIsNeverTheTip) {
    // Dark surround outside a circle; the tool runs out of view: no tip to find.
    Scene s = shaft({0, 240}, {640, 240}, 30, 330.0);
    cv::Mat mask(s.img.size(), CV_8U, cv::Scalar(255));
    cv::circle(mask, cv::Point(320, 240), 230, cv::Scalar(0), cv::FILLED);
    s.img.setTo(cv::Scalar(0, 0, 0), mask);
    const TipResult r = extract_tip(view(s.img), s.edges, s.toward_tip, {320, 240, 230});
    EXPECT_FALSE(r.found) << "at " << r.tip.x << "," << r.tip.y << " contrast " << r.contrast;
    // Without the field of view, the rim would have been taken for the tip.
    const TipResult naive = extract_tip(view(s.img), s.edges, s.toward_tip, {});
    EXPECT_TRUE(naive.found);
    EXPECT_NEAR(naive.tip.x, 550, 3.0);
}

TEST(TipExtractor, NotBeyondWhereTheEdgesMeet) {
    // Edges converging (perspective): their lines meet at x = 300; a strong change
    // past it (a bright instrument tray at x = 330) is out of the search area.
    Scene s = shaft({0, 240}, {260, 240}, 30, 20.0);
    s.edges.e1 = {{0, 225}, {240, 237}};
    s.edges.e2 = {{0, 255}, {240, 243}};
    cv::rectangle(s.img, cv::Rect(330, 200, 40, 80), cv::Scalar(10, 10, 10), cv::FILLED);
    const TipResult r = extract_tip(view(s.img), s.edges, s.toward_tip, {});
    ASSERT_TRUE(r.found);
    EXPECT_NEAR(r.tip.x, 260, 2.0);
}

}  // namespace
}  // namespace endotower::vision
