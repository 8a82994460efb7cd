// eval readers: malformed input gives exact messages; the real annotation files in
// ../shared/data read as their README describes.
#include <cmath>
#include <fstream>

#include "endotower/eval/analysis_trace.hpp"
#include "endotower/eval/annotations.hpp"
#include "endotower/eval/truth.hpp"
#include "eval_test_util.hpp"

namespace endotower::eval {
namespace {

using namespace test;

const fs::path kData = ENDOTOWER_SHARED_DATA;

#define REQUIRE_DATA(path)                                                                   \
    if (!fs::exists(kData / (path)))                                                         \
        GTEST_SKIP() << "real data absent: " << (kData / (path)).string()                    \
                     << " (../shared/data is not part of a fresh clone)";

std::string truth_error(const std::vector<std::string>& lines) {
    const fs::path d = temp_dir("truth");
    const std::string p = write_lines(d / "truth.jsonl", lines);
    std::vector<TruthFrame> f;
    std::string e;
    EXPECT_FALSE(read_truth(p, f, e));
    const std::string prefix = p + ":";
    EXPECT_EQ(e.rfind(prefix, 0), 0u) << e;
    return e.substr(prefix.size());
}

std::string trace_error(const std::vector<std::string>& lines) {
    const fs::path d = temp_dir("trace");
    const std::string p = write_lines(d / "trace.jsonl", lines);
    std::vector<AnalysisFrame> f;
    std::string e;
    EXPECT_FALSE(read_analysis_trace(p, f, e));
    const std::string prefix = p + ":";
    EXPECT_EQ(e.rfind(prefix, 0), 0u) << e;
    return e.substr(prefix.size());
}

TEST(TruthReader, ReadsTheDocumentedExample) {
    const std::string example =
        R"({"frame":12,"t_ns":400000000,"camera":{"width":640,"height":480},"light":0.62,"speed_cm_s":3.1,"tools":[{"id":0,"visible":true,"visible_fraction":1.0,"tip_px":[301.2,250.7],"head_px":[318.9,262.0],"axis_deg":32.6,"width_px":41.3,"tip_mm":[-3.1,1.9,62.0],"axis_dir":[0.52,0.31,-0.79],"diameter_mm":5,"tip_type":"grasper","jaw":"open","gesture":"open_grasper","markers":[]}],"gesture":null,"regions":[],"events":["dwell"],"factors":{"speed":"0-4","light":"46-100","distractors":false}})";
    TruthFrame f;
    std::string e;
    ASSERT_TRUE(parse_truth_line(example, f, e)) << e;
    EXPECT_EQ(f.frame, 12);
    ASSERT_EQ(f.tools.size(), 1u);
    EXPECT_DOUBLE_EQ(f.tools[0].tip_px.x, 301.2);
    EXPECT_DOUBLE_EQ(f.tools[0].head_px.y, 262.0);
    EXPECT_DOUBLE_EQ(f.tools[0].width_px, 41.3);
    ASSERT_TRUE(f.tools[0].tip_mm);
    EXPECT_DOUBLE_EQ(f.tools[0].tip_mm->z, 62.0);
    EXPECT_EQ(f.tools[0].gesture, "open_grasper");
    EXPECT_FALSE(f.gesture);
    EXPECT_EQ(f.events, std::vector<std::string>{"dwell"});
    ASSERT_EQ(f.factors.size(), 3u);
    EXPECT_EQ(f.factors[0], (std::pair<std::string, std::string>{"distractors", "no"}));
    EXPECT_EQ(f.factors[1], (std::pair<std::string, std::string>{"light", "46-100"}));
    EXPECT_DOUBLE_EQ(f.light, 0.62);
}

TEST(TruthReader, MalformedLinesNameLineAndField) {
    const std::string ok = truth_line(0, gtool(0, 1, 2, 0, 10));
    EXPECT_EQ(truth_error({ok, R"({"frame":1})"}), "2: missing field 'tools'");
    EXPECT_EQ(truth_error({R"({"frame":0,"tools":[{"id":0,"visible":true,"tip_px":[1],"axis_deg":0,"width_px":3}]})"}),
              "1: field 'tools[0].tip_px' must be [x, y] (two numbers)");
    EXPECT_EQ(truth_error({ok, "", "{\"frame\":1,"}), "3: not valid JSON");
    EXPECT_EQ(truth_error({ok, truth_line(0, "")}), "2: field 'frame' must increase from line to line (0 after 0)");
    EXPECT_EQ(truth_error({truth_line(0, "", R"("gesture":"wave")")}),
              "1: field 'gesture' must be null or a gesture label (cross, triangle, ...)");
    EXPECT_EQ(truth_error({truth_line(0, gtool(0, 1, 2, 0, 0))}),
              "1: field 'tools[0].width_px' must be > 0 for a visible tool");
    EXPECT_EQ(truth_error({truth_line(0, "", R"("regions":[{"id":1,"polygon_px":[[0,0],[1,1]]}])")}),
              "1: field 'regions[0].polygon_px' must be [[x, y], ...] with at least 3 points");
    EXPECT_EQ(truth_error({"[1,2]"}), "1: a line must be a JSON object");
}

TEST(TraceReader, AnalysisMembersAndMalformedOnes) {
    AnalysisFrame f;
    std::string e;
    ASSERT_TRUE(parse_analysis_line(trace_line(3, R"("status":{"light":0.5},"tools":[)" + ttool(2, 1, 2, 45, 3, 4, "[1,2,3]") + "]"), f, e)) << e;
    EXPECT_EQ(f.frame, 3);
    ASSERT_TRUE(f.has_tools);
    EXPECT_DOUBLE_EQ(f.tools[0].head_px.x, 3.0);
    ASSERT_TRUE(f.tools[0].tip_mm);
    EXPECT_DOUBLE_EQ(f.tools[0].tip_mm->z, 3.0);
    EXPECT_FALSE(f.gesture);
    ASSERT_TRUE(parse_analysis_line(trace_line(4), f, e));
    EXPECT_FALSE(f.has_tools);

    EXPECT_EQ(trace_error({trace_line(0), R"({"frame":1})"}), "2: missing field 'seq'");
    EXPECT_EQ(trace_error({trace_line(0, R"("tools":[)" + ttool(0, 1, 1, 0) + R"(,{"id":1,"tip_px":[1,2],"axis_deg":0,"confidence":1}])")}),
              "1: missing field 'tools[1].head_px'");
    EXPECT_EQ(trace_error({trace_line(0, R"("tools":{})")}), "1: field 'tools' must be an array");
    EXPECT_EQ(trace_error({trace_line(0, R"("gesture":{"label":"wave","fired":false})")}),
              "1: field 'gesture.label' must be null or a gesture label (open_grasper, closed_grasper, "
              "open_scissors, closed_scissors, cross, triangle, double_triangle)");
    EXPECT_EQ(trace_error({trace_line(0, R"("gesture":{"label":null})")}), "1: missing field 'gesture.fired'");
    EXPECT_EQ(trace_error({trace_line(0, R"("regions":[{"id":1,"polygon_px":[[0,0],[1,0],[1,1]],"state":"gone"}])")}),
              "1: field 'regions[0].state' must be \"tracked\" or \"lost\"");
    EXPECT_EQ(trace_error({trace_line(0, R"("tools":[)" + ttool(0, 1, 1, 0, -1, -1, "[1,2]") + "]")}),
              "1: field 'tools[0].tip_mm' must be [x, y, z] (three numbers) or null");
    EXPECT_EQ(trace_error({trace_line(5), trace_line(5)}), "2: field 'frame': frame 5 is listed twice");
}

TEST(SznitmanReader, RealTrainFileKeepsTheFirstOfDuplicates) {
    REQUIRE_DATA("sznitman_lap/train.xml");
    SznitmanAnnotations a;
    std::string e;
    ASSERT_TRUE(read_sznitman((kData / "sznitman_lap/train.xml").string(), a, e)) << e;
    EXPECT_EQ(a.declared_frames, 400);
    EXPECT_EQ(a.frames.size(), 400u);
    // 407 <frame> entries: 1204, 1205, 1330, 1361, 1468 twice and 1401 three times.
    EXPECT_EQ(a.duplicates_dropped, 7);
    // 57 frames with one tool, 343 with two.
    EXPECT_EQ(a.tool_frames(), 743);
    EXPECT_EQ(a.frames.front().index, 1175);
    EXPECT_DOUBLE_EQ(a.frames.front().tools[0].row, 122);
    EXPECT_DOUBLE_EQ(a.frames.front().tools[0].col, 245);
    EXPECT_DOUBLE_EQ(a.frames.front().tools[0].scale, 67.521364);
    EXPECT_DOUBLE_EQ(a.frames.front().tools[0].angle_rad, 5.852859);
    for (const SznitmanFrame& f : a.frames)
        if (f.index == 1204) {
            ASSERT_EQ(f.tools.size(), 2u);
            EXPECT_DOUBLE_EQ(f.tools[0].col, 229);  // the first entry (the second says 224)
            EXPECT_DOUBLE_EQ(f.tools[1].row, 112);
        }
    EXPECT_EQ(a.frames.back().index, 1574);
}

TEST(SznitmanReader, MalformedFilesNameTheLine) {
    const fs::path d = temp_dir("sz");
    auto err = [&](const std::string& text) {
        std::ofstream(d / "a.xml") << text;
        SznitmanAnnotations a;
        std::string e;
        EXPECT_FALSE(read_sznitman((d / "a.xml").string(), a, e));
        return e.substr((d / "a.xml").string().size());
    };
    const std::string head = "<?xml version='1.0'?>\n<tagDocument>\n";
    EXPECT_EQ(err(head + "<frame>\n<frame>\n<PositionIndex> 1 </PositionIndex>\n</frame>\n</tagDocument>\n"),
              ":4: <frame> inside <frame> (missing </frame>)");
    EXPECT_EQ(err(head + "<frame>\n<PositionIndex> 1 </PositionIndex>\n<tool> 1 2 3 </tool>\n</frame>\n</tagDocument>\n"),
              ":5: <tool> needs 4 numbers ROW COL SCALE ANGLE, got '1 2 3'");
    EXPECT_EQ(err(head + "<frame>\n<tool> 1 2 3 4 </tool>\n</frame>\n</tagDocument>\n"),
              ":3: <frame> without <PositionIndex>");
    EXPECT_EQ(err("<svg>\n"), ":1: expected <tagDocument> (a Sznitman annotation file)");
    EXPECT_EQ(err(head + "<numberOfFrames> 2 </numberOfFrames>\n<frame>\n<PositionIndex> 1 </PositionIndex>\n</frame>\n</tagDocument>\n"),
              ":1: <numberOfFrames> says 2 but 1 distinct frames are listed");
}

TEST(MaskReader, RealToolMasks) {
    REQUIRE_DATA("endotip/demo_seg.png");
    ToolMask m;
    std::string e;
    ASSERT_TRUE(read_tool_mask((kData / "endotip/demo_seg.png").string(), m, e)) << e;
    EXPECT_EQ(m.width, 980);
    EXPECT_EQ(m.height, 988);
    ASSERT_EQ(m.components.size(), 2u);
    // The README's tool boxes (x0, y0, x1, y1): (538,437,907,815) and (161,583,470,894).
    std::vector<std::array<int, 4>> boxes;
    for (const MaskComponent& c : m.components) boxes.push_back({c.x0, c.y0, c.x1, c.y1});
    std::sort(boxes.begin(), boxes.end());
    for (int k = 0; k < 4; ++k) {
        EXPECT_NEAR(boxes[0][k], (std::array<int, 4>{161, 583, 470, 894})[k], 1);
        EXPECT_NEAR(boxes[1][k], (std::array<int, 4>{538, 437, 907, 815})[k], 1);
    }
    for (const char* name : {"endovis17_demo/left_frame.png", "endovis17_demo/right_frame.png"}) {
        ASSERT_TRUE(read_tool_mask((kData / name).string(), m, e)) << e;
        EXPECT_EQ(m.width, 1920);
        EXPECT_GE(m.components.size(), 1u);
        EXPECT_GT(m.components[0].area, 1000);
    }
    EXPECT_FALSE(read_tool_mask((kData / "sznitman_lap/train.xml").string(), m, e));
    EXPECT_NE(e.find("train.xml: not an image"), std::string::npos) << e;
}

TEST(HomographyReader, FileStorageAndModelText) {
    REQUIRE_DATA("homography_pairs/graf_model.txt");
    Homography h;
    std::string e;
    ASSERT_TRUE(read_homography((kData / "opencv_samples/H1to3p.xml").string(), h, e)) << e;
    EXPECT_DOUBLE_EQ(h[0], 7.6285898e-01);
    EXPECT_DOUBLE_EQ(h[2], 2.2567123e+02);
    EXPECT_DOUBLE_EQ(h[8], 1.0);
    // *_model.txt maps B to A. In *_pts.txt (A point first) the label-1 rows are exact
    // correspondences of the model; the label-0 rows are matched points (median error
    // a few px); applied the other way (A to B) the model is hundreds of px off.
    for (const char* pair : {"graf", "boat", "adam"}) {
        ASSERT_TRUE(read_homography((kData / "homography_pairs" / (std::string(pair) + "_model.txt")).string(), h, e)) << e;
        std::ifstream pts(kData / "homography_pairs" / (std::string(pair) + "_pts.txt"));
        double ax, ay, aw, bx, by, bw, label, exact_worst = 0;
        std::vector<double> matched, reversed;
        while (pts >> ax >> ay >> aw >> bx >> by >> bw >> label) {
            const Point2 a = apply_homography(h, {bx, by});
            const double err = std::hypot(a.x - ax, a.y - ay);
            if (label == 1) exact_worst = std::max(exact_worst, err);
            if (label != 0) continue;
            matched.push_back(err);
            const Point2 b = apply_homography(h, {ax, ay});
            reversed.push_back(std::hypot(b.x - bx, b.y - by));
        }
        ASSERT_GT(matched.size(), 5u) << pair;
        EXPECT_LT(exact_worst, 1e-6) << pair;
        std::sort(matched.begin(), matched.end());
        std::sort(reversed.begin(), reversed.end());
        EXPECT_LT(matched[matched.size() / 2], 5.0) << pair;
        EXPECT_GT(reversed[reversed.size() / 2], 50.0) << pair;
    }
    Homography inv;
    ASSERT_TRUE(invert_homography(h, inv));
    const Point2 p = apply_homography(inv, apply_homography(h, {100, 200}));
    EXPECT_NEAR(p.x, 100, 1e-9);
    EXPECT_NEAR(p.y, 200, 1e-9);
    const fs::path d = temp_dir("h");
    std::ofstream(d / "h.txt") << "1 0 0\n0 1 x\n";
    EXPECT_FALSE(read_homography((d / "h.txt").string(), h, e));
    EXPECT_EQ(e, (d / "h.txt").string() + ":2: 'x' is not a number");
    std::ofstream(d / "s.txt") << "1 0 0\n0 1 0\n";
    EXPECT_FALSE(read_homography((d / "s.txt").string(), h, e));
    EXPECT_EQ(e, (d / "s.txt").string() + ":2: 6 numbers, a 3x3 homography needs 9");
}

}  // namespace
}  // namespace endotower::eval
