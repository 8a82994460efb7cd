// Truth derived from tool masks and homographies, and `eval --mask` / `--homography`.
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <fstream>

#include "endotower/eval/derived_truth.hpp"
#include "eval_test_util.hpp"

namespace endotower::eval {
namespace {

using namespace test;

// A binary PGM (OpenCV reads it as a mask) with filled axis-aligned boxes.
struct Box {
    int x0, y0, x1, y1;  // inclusive
};
fs::path write_mask(const fs::path& path, int w, int h, const std::vector<Box>& boxes) {
    std::vector<unsigned char> px(static_cast<std::size_t>(w) * h, 0);
    for (const Box& b : boxes)
        for (int y = b.y0; y <= b.y1; ++y)
            for (int x = b.x0; x <= b.x1; ++x) px[static_cast<std::size_t>(y) * w + x] = 255;
    std::ofstream out(path, std::ios::binary);
    out << "P5\n" << w << " " << h << "\n255\n";
    out.write(reinterpret_cast<const char*>(px.data()), static_cast<std::streamsize>(px.size()));
    return path;
}

ToolMask read_mask(const fs::path& p) {
    ToolMask m;
    std::string error;
    EXPECT_TRUE(read_tool_mask(p.string(), m, error)) << error;
    return m;
}

TEST(ToolsFromMask, HorizontalToolFromTheLeftBorder) {
    const fs::path d = temp_dir("mask_h");
    // 100 px long, 10 px wide, touching the left border: the tip is at the right end.
    const ToolMask m = read_mask(write_mask(d / "m.pgm", 200, 100, {{0, 45, 99, 54}}));
    const std::vector<TruthTool> t = tools_from_mask(m);
    ASSERT_EQ(t.size(), 1u);
    EXPECT_NEAR(t[0].tip_px.x, 97.5, 1e-9);  // mean of columns 96..99 (3 px band)
    EXPECT_NEAR(t[0].tip_px.y, 49.5, 1e-9);
    EXPECT_NEAR(std::abs(t[0].axis_deg), 180.0, 1e-6);  // tip towards the shaft: leftwards
    EXPECT_NEAR(t[0].width_px, 10.0, 1e-9);               // 1000 px / 100 px
}

TEST(ToolsFromMask, TwoToolsLargestFirstEachTipAwayFromItsBorder) {
    const fs::path d = temp_dir("mask_two");
    // A vertical tool from the bottom border (8 x 60) and a larger one from the right (120 x 12).
    const ToolMask m = read_mask(write_mask(d / "m.pgm", 300, 200, {{40, 140, 47, 199}, {180, 20, 299, 31}}));
    const std::vector<TruthTool> t = tools_from_mask(m);
    ASSERT_EQ(t.size(), 2u);
    EXPECT_EQ(t[0].id, 1);
    EXPECT_NEAR(t[0].tip_px.x, 181.5, 1e-9);  // columns 180..183
    EXPECT_NEAR(t[0].tip_px.y, 25.5, 1e-9);
    EXPECT_NEAR(t[0].axis_deg, 0.0, 1e-6);  // towards the right border
    EXPECT_NEAR(t[0].width_px, 12.0, 1e-9);
    EXPECT_NEAR(t[1].tip_px.x, 43.5, 1e-9);
    EXPECT_NEAR(t[1].tip_px.y, 141.5, 1e-9);  // rows 140..143
    EXPECT_NEAR(t[1].axis_deg, 90.0, 1e-6);   // towards the bottom (y down)
    EXPECT_NEAR(t[1].width_px, 8.0, 1e-9);
}

TEST(RegionTruthFromHomography, MapsThePolygonToTheLastFrame) {
    const Homography h = {2, 0, 10, 0, 2, -5, 0, 0, 1};
    std::vector<TruthFrame> gt;
    std::string error;
    ASSERT_TRUE(region_truth_from_homography({{{0, 0}, {10, 0}, {10, 10}}}, h, 3, 9, gt, error)) << error;
    ASSERT_EQ(gt.size(), 2u);
    EXPECT_EQ(gt[0].frame, 3);
    EXPECT_EQ(gt[1].frame, 9);
    ASSERT_EQ(gt[1].regions.size(), 1u);
    EXPECT_DOUBLE_EQ(gt[1].regions[0].polygon_px[2].x, 30.0);
    EXPECT_DOUBLE_EQ(gt[1].regions[0].polygon_px[2].y, 15.0);
    const Homography to_infinity = {1, 0, 0, 0, 1, 0, 1, 0, -5};  // w = x - 5
    EXPECT_FALSE(region_truth_from_homography({{{5, 0}, {6, 0}, {6, 1}}}, to_infinity, 0, 1, gt, error));
    EXPECT_NE(error.find("infinity"), std::string::npos);
}

TEST(ParsePolygon, AcceptsPairsRejectsMalformed) {
    std::vector<Point2> p;
    std::string error;
    ASSERT_TRUE(parse_polygon("1,2 3.5,4  -5,6e1", p, error)) << error;
    ASSERT_EQ(p.size(), 3u);
    EXPECT_DOUBLE_EQ(p[2].y, 60.0);
    EXPECT_FALSE(parse_polygon("1,2 3,4", p, error));
    EXPECT_NE(error.find("at least 3"), std::string::npos);
    EXPECT_FALSE(parse_polygon("1,2 3;4 5,6", p, error));
    EXPECT_NE(error.find("'3;4'"), std::string::npos);
}


TEST(EvalCommand, MaskTruthScoresTheMaskedFrameByTheBookRule) {
    const fs::path d = temp_dir("cli_mask");
    const fs::path mask = write_mask(d / "m.pgm", 200, 100, {{0, 45, 99, 54}});
    // Frame 0: 6 px off (within 2 x 10 px) pointing back along the shaft: success.
    // Frame 1 has no mask and is not scored.
    const std::string good = write_lines(d / "good.jsonl", {trace_line(0, R"("tools":[)" + ttool(1, 97.5 + 6, 49.5, 178) + "]"),
                                                             trace_line(1, R"("tools":[)" + ttool(1, 5, 5, 0) + "]")});
    CommandRun r = run_eval("--trace " + good + " --mask " + mask.string() + " --min-success 1");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("success 100.0 % (1/1); tip error mean 6.00 px"), std::string::npos) << r.output;
    // Pointing the wrong way (tip towards the tip side): the axis rule fails it.
    const std::string wrong = write_lines(d / "wrong.jsonl", {trace_line(0, R"("tools":[)" + ttool(1, 97.5, 49.5, 0) + "]")});
    EXPECT_EQ(run_eval("--trace " + wrong + " --mask 0:" + mask.string() + " --min-success 1").status, 1);
    // The mask given for frame 1 instead scores frame 1's tool, which is far off.
    r = run_eval("--trace " + good + " --mask 1:" + mask.string() + " --min-success 1");
    EXPECT_EQ(r.status, 1) << r.output;
    r = run_eval("--trace " + good + " --mask " + (d / "absent.png").string());
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("absent.png"), std::string::npos) << r.output;
}

TEST(EvalCommand, HomographyTruthScoresTheLastFrameCorners) {
    const fs::path d = temp_dir("cli_h");
    std::ofstream(d / "h.txt") << "1 0 10\n0 1 5\n0 0 1\n";  // first -> last: shift (10, 5)
    auto region = [](double dx, double dy) {
        char b[256];
        std::snprintf(b, sizeof b, R"("regions":[{"id":1,"polygon_px":[[%g,%g],[%g,%g],[%g,%g],[%g,%g]],"state":"tracked","inliers":40}])",
                      100 + dx, 100 + dy, 200 + dx, 100 + dy, 200 + dx, 200 + dy, 100 + dx, 200 + dy);
        return std::string(b);
    };
    const std::string trace = write_lines(d / "t.jsonl", {trace_line(0, region(0, 0)), trace_line(1, region(10, 5))});
    CommandRun r = run_eval("--trace " + trace + " --homography " + (d / "h.txt").string() + " --max-corner-error 0.01");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("regions: 1 region-frames: GOOD 1, OK 0, FAIL 0; mean corner error 0.00 px"), std::string::npos)
        << r.output;
    // Read the other way round, the truth is shifted by (-10, -5): 22.36 px from the trace.
    r = run_eval("--trace " + trace + " --homography " + (d / "h.txt").string() +
                 " --homography-maps last-to-first --max-corner-error 2");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("mean corner error 22.36 px"), std::string::npos) << r.output;
    // A region given on the command line is scored at the first frame too.
    r = run_eval("--trace " + trace + " --homography " + (d / "h.txt").string() +
                 " --region \"100,100 200,100 200,200 100,200\"");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("regions: 2 region-frames: GOOD 2"), std::string::npos) << r.output;
    r = run_eval("--trace " + trace + " --homography " + (d / "h.txt").string() + " --region \"1,2 3\"");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("--region"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace endotower::eval

namespace endotower::eval {
namespace {

// The endotip mask (real frame, two tools from the border): each derived tip lies in
// its tool's box from the data README and is the end farther from the image border.
TEST(ToolsFromMask, RealEndotipMask) {
    const fs::path mask = fs::path(ENDOTOWER_SHARED_DATA) / "endotip/demo_seg.png";
    if (!fs::exists(mask)) GTEST_SKIP() << "real data absent: " << mask.string() << " (../shared/data is not part of a fresh clone)";
    const std::vector<TruthTool> t = tools_from_mask(read_mask(mask));
    ASSERT_EQ(t.size(), 2u);
    const Box boxes[2] = {{538, 437, 907, 815}, {161, 583, 470, 894}};
    for (const TruthTool& tool : t) {
        int inside = 0;
        for (const Box& b : boxes)
            inside += tool.tip_px.x >= b.x0 && tool.tip_px.x <= b.x1 && tool.tip_px.y >= b.y0 && tool.tip_px.y <= b.y1;
        EXPECT_GE(inside, 1) << tool.tip_px.x << "," << tool.tip_px.y;
        EXPECT_GT(tool.width_px, 10.0);
        // The shaft side (along axis_deg from the tip) reaches nearer the image border.
        const double a = tool.axis_deg * M_PI / 180.0;
        const Point2 back{tool.tip_px.x + 200 * std::cos(a), tool.tip_px.y + 200 * std::sin(a)};
        auto border = [](Point2 p) { return std::min({p.x, p.y, 979 - p.x, 987 - p.y}); };
        EXPECT_LT(border(back), border(tool.tip_px));
    }
}

}  // namespace
}  // namespace endotower::eval
