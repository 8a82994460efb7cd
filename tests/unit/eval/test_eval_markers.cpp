// Strip-marker scores (tables 3.1/3.2) on hand-made traces and truths with known answers.
#include <string>
#include <vector>

#include "endotower/eval/marker_metrics.hpp"
#include "eval_test_util.hpp"

namespace endotower::eval {
namespace {

using namespace test;

// Three strips 20 px apart; strip 0 (nearest the tip) at (100, 100), (10, -10, 50) mm.
std::string markers_of(bool strip0_visible) {
    return std::string(
               R"(,"markers":[{"strip":0,"center_px":[100,100],"corners_px":[[0,0],[0,0],[0,0],[0,0]],)") +
           R"("center_mm":[10,-10,50],"visible":)" + (strip0_visible ? "true" : "false") + "}," +
           R"({"strip":1,"center_px":[120,100],"corners_px":[[0,0],[0,0],[0,0],[0,0]],"center_mm":[13,-10,48],"visible":true},)" +
           R"({"strip":2,"center_px":[140,100],"corners_px":[[0,0],[0,0],[0,0],[0,0]],"center_mm":[16,-10,46],"visible":true}])";
}

TruthFrame truth(int frame, bool strip0_visible) {
    TruthFrame f;
    std::string e;
    const std::string tool =
        R"({"id":0,"visible":true,"tip_px":[90,100],"axis_deg":0,"width_px":20)" +
        markers_of(strip0_visible) + "}";
    EXPECT_TRUE(parse_truth_line(truth_line(frame, tool), f, e)) << e;
    return f;
}

AnalysisFrame trace(int frame, const std::string& markers) {
    AnalysisFrame f;
    std::string e;
    EXPECT_TRUE(parse_analysis_line(trace_line(frame, R"("markers":)" + markers), f, e)) << e;
    return f;
}

// Exact errors: depth 55 vs 50 (10 %), x 11 vs 10 (10 %), y -9 vs -10 (10 %); the
// second frame picks strip 1 while strip 0 is visible (found, wrong strip: not within
// half a diameter of strip 0); the third hides strip 0, so strip 1 is the target and a
// marker on it is right; the fourth has no located marker.
TEST(MarkerScore, ErrorsStripChoiceAndTable) {
    const std::vector<TruthFrame> gt = {truth(0, true), truth(1, true), truth(2, false),
                                        truth(3, true)};
    const std::vector<AnalysisFrame> tr = {
        trace(0, R"([{"center_px":[101,100],"diameter_px":20,"strips":3,"tip_mm":[11,-9,55]}])"),
        trace(1, R"([{"center_px":[120,100],"diameter_px":18,"strips":3,"tip_mm":[13,-10,48]}])"),
        trace(2, R"([{"center_px":[121,100],"diameter_px":18,"strips":2,"tip_mm":[13,-10,48]}])"),
        trace(3, R"([{"center_px":[100,100],"diameter_px":20,"strips":3,"tip_mm":null}])")};
    const MarkerScore s = score_markers(gt, tr);
    EXPECT_EQ(s.targets, 4);
    EXPECT_EQ(s.matched, 3);
    EXPECT_EQ(s.right_strip, 3);
    EXPECT_EQ(s.located, 2);
    EXPECT_NEAR(s.depth_error, 0.5 * (0.10 + 0.0), 1e-12);
    EXPECT_NEAR(s.x_error, 0.5 * (0.10 + 0.0), 1e-12);
    EXPECT_NEAR(s.y_error, 0.5 * (0.10 + 0.0), 1e-12);
    ASSERT_EQ(s.points.size(), 2u);
    const std::string text = render_marker_summary(s);
    EXPECT_NE(text.find("| 50 mm | | (11.0, -9.0) 55.0 |"), std::string::npos) << text;
    EXPECT_NE(text.find("| 48 mm | (13.0, -10.0) 48.0 | |"), std::string::npos) << text;
    EXPECT_NE(text.find("4 targets, 3 found, 3 on the right strip, 2 located"), std::string::npos)
        << text;
}

// Malformed members name the field.
TEST(MarkerScore, BadMembersAreNamed) {
    AnalysisFrame f;
    std::string e;
    EXPECT_FALSE(parse_analysis_line(
        trace_line(0, R"("markers":[{"center_px":[1],"diameter_px":2,"strips":1}])"), f, e));
    EXPECT_NE(e.find("markers[0].center_px"), std::string::npos) << e;
    TruthFrame g;
    EXPECT_FALSE(parse_truth_line(
        truth_line(0, gtool(0, 1, 1, 0, 5, true,
                            R"(,"markers":[{"strip":0,"center_px":[1,1],"visible":true}])")),
        g, e));
    EXPECT_NE(e.find("markers[0].center_mm"), std::string::npos) << e;
}

}  // namespace
}  // namespace endotower::eval
