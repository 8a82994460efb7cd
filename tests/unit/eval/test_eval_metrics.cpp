// eval metrics on hand-made traces and truths with known answers.
#include <cmath>

#include "endotower/eval/assignment.hpp"
#include "endotower/eval/gesture_metrics.hpp"
#include "endotower/eval/region_metrics.hpp"
#include "endotower/eval/tool_metrics.hpp"
#include "eval_test_util.hpp"

namespace endotower::eval {
namespace {

using namespace test;

std::vector<TruthFrame> truth_of(const std::vector<std::string>& lines) {
    std::vector<TruthFrame> out;
    for (const std::string& l : lines) {
        TruthFrame f;
        std::string e;
        EXPECT_TRUE(parse_truth_line(l, f, e)) << e << " in " << l;
        out.push_back(f);
    }
    return out;
}
std::vector<AnalysisFrame> trace_of(const std::vector<std::string>& lines) {
    std::vector<AnalysisFrame> out;
    for (const std::string& l : lines) {
        AnalysisFrame f;
        std::string e;
        EXPECT_TRUE(parse_analysis_line(l, f, e)) << e << " in " << l;
        out.push_back(f);
    }
    return out;
}

TEST(Assignment, FindsTheMinimumTotalCost) {
    // Optimum 1 + 2 + 2 = 5 (row 0 -> 1, row 1 -> 0, row 2 -> 2); greedy on the
    // smallest cell (row 1 -> 1, cost 0) would end at 0 + 3 + 3 = 6.
    const std::vector<double> c = {4, 1, 3, 2, 0, 5, 3, 2, 2};
    EXPECT_EQ(assign_min_cost(c, 3, 3), (std::vector<int>{1, 0, 2}));
    // More rows than columns: the costly row is left over.
    EXPECT_EQ(assign_min_cost({1, 9, 9, 9, 9, 1}, 3, 2), (std::vector<int>{0, -1, 1}));
    EXPECT_EQ(assign_min_cost({5, 1, 7}, 1, 3), (std::vector<int>{1}));
    EXPECT_EQ(assign_min_cost({}, 2, 0), (std::vector<int>{-1, -1}));
}

TEST(Statistics, MeanAndNearestRankP95) {
    std::vector<double> v;
    for (int i = 20; i >= 1; --i) v.push_back(i);
    EXPECT_DOUBLE_EQ(percentile_nearest_rank(v, 95), 19.0);
    EXPECT_DOUBLE_EQ(percentile_nearest_rank({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, 95), 10.0);
    EXPECT_DOUBLE_EQ(mean_of({1, 2, 6}), 3.0);
    EXPECT_DOUBLE_EQ(mean_of({}), 0.0);
    EXPECT_DOUBLE_EQ(direction_diff_deg(175, -175), 10.0);
    EXPECT_DOUBLE_EQ(direction_diff_deg(90, -90), 180.0);
    EXPECT_DOUBLE_EQ(line_diff_deg(90, -90), 0.0);
    EXPECT_DOUBLE_EQ(line_diff_deg(10, 350), 20.0);
    EXPECT_DOUBLE_EQ(line_diff_deg(0, 110), 70.0);
}

TEST(ToolScore, BookRuleCountsErrorsAndFalsePositives) {
    // One tool 10 px wide: the tolerance is 20 px.
    const auto truth = truth_of({
        truth_line(0, gtool(0, 100, 100, 175, 10)),
        truth_line(1, gtool(0, 100, 100, 0, 10)),
        truth_line(2, gtool(0, 100, 100, 0, 10)),
        truth_line(3, gtool(0, 100, 100, 90, 10)),
        truth_line(4, gtool(0, 100, 100, 0, 10)),
        truth_line(5, gtool(0, 100, 100, 0, 10, false)),
    });
    const auto trace = trace_of({
        trace_line(0, R"("tools":[)" + ttool(3, 103, 104, -175) + "]"),  // 5 px, 10 deg: success
        trace_line(1, R"("tools":[)" + ttool(3, 100, 120, 20) + "]"),    // 20 px, 20 deg: success (not greater)
        trace_line(2, R"("tools":[)" + ttool(3, 121, 100, 0) + "]"),     // 21 px: fails
        trace_line(3, R"("tools":[)" + ttool(3, 100, 100, -90) + "]"),   // pointing the other way: fails
        trace_line(4, R"("tools":[])"),                                  // nothing found: fails
        trace_line(5, R"("tools":[)" + ttool(3, 50, 50, 0) + "]"),       // tool hidden: false positive
    });
    const ToolScore s = score_tools(truth, trace);
    EXPECT_EQ(s.frames, 6);
    EXPECT_EQ(s.tool_frames, 5);
    EXPECT_EQ(s.matched, 4);
    EXPECT_EQ(s.successes, 2);
    EXPECT_DOUBLE_EQ(s.success_rate, 0.4);
    EXPECT_DOUBLE_EQ(s.mean_error_px, (5.0 + 20 + 21 + 0) / 4);
    EXPECT_DOUBLE_EQ(s.p95_error_px, 21.0);
    EXPECT_EQ(s.false_positives, 1);
    EXPECT_DOUBLE_EQ(s.false_positives_per_frame, 1.0 / 6);
    ASSERT_EQ(s.pairs.size(), 5u);
    EXPECT_DOUBLE_EQ(s.pairs[0].axis_error_deg, 10.0);
    EXPECT_DOUBLE_EQ(s.pairs[3].axis_error_deg, 180.0);
    EXPECT_EQ(s.pairs[4].trace_id, -1);
    EXPECT_FALSE(s.identity_consistency);  // one tool: no identity to keep
    EXPECT_EQ(s.with_mm, 0);
}

TEST(ToolScore, OptimalAssignmentBeatsNearestFirst) {
    // Truth tips at x = 0 and x = 4, trace tips at x = 3 and x = 8, tolerance 5 px.
    // Nearest-first pairs 4<->3 and leaves 0<->8 (fail); the optimum pairs 0<->3 and 4<->8.
    const auto truth = truth_of({truth_line(0, gtool(0, 100, 50, 0, 2.5) + "," + gtool(1, 104, 50, 0, 2.5))});
    const auto trace = trace_of({trace_line(0, R"("tools":[)" + ttool(5, 103, 50, 0) + "," + ttool(6, 108, 50, 0) + "]")});
    const ToolScore s = score_tools(truth, trace);
    EXPECT_EQ(s.successes, 2);
    EXPECT_EQ(s.pairs[0].trace_id, 5);
    EXPECT_EQ(s.pairs[1].trace_id, 6);
    EXPECT_DOUBLE_EQ(s.mean_error_px, 3.5);
}

TEST(ToolScore, SwappedIdsAreMatchedByPositionAndIdentityIsMeasured) {
    std::vector<std::string> gt, tr;
    for (int f = 0; f < 4; ++f) {
        gt.push_back(truth_line(f, gtool(0, 100, 100, 30, 10) + "," + gtool(1, 300, 300, 150, 10)));
        // The trace lists the tools in the other order, with its own ids; in frame 3
        // it swaps its ids.
        const int a = f < 3 ? 7 : 9, b = f < 3 ? 9 : 7;
        tr.push_back(trace_line(f, R"("tools":[)" + ttool(a, 301, 300, 150) + "," + ttool(b, 100, 101, 30) + "]"));
    }
    const ToolScore s = score_tools(truth_of(gt), trace_of(tr));
    EXPECT_EQ(s.successes, 8);
    EXPECT_EQ(s.false_positives, 0);
    EXPECT_DOUBLE_EQ(s.mean_error_px, 1.0);
    EXPECT_EQ(s.pairs[0].truth_id, 0);
    EXPECT_EQ(s.pairs[0].trace_id, 9);
    EXPECT_EQ(s.pairs[1].trace_id, 7);
    ASSERT_TRUE(s.identity_consistency);
    EXPECT_DOUBLE_EQ(*s.identity_consistency, 6.0 / 8);
    EXPECT_EQ(s.identity_pairs, 8);
}

TEST(ToolScore, ThreeDimensionalErrorWhereBothDepthsAreKnown) {
    const auto truth = truth_of({truth_line(0, gtool(0, 10, 10, 0, 10, true, R"(,"tip_mm":[0,0,50])")),
                                 truth_line(1, gtool(0, 10, 10, 0, 10, true, R"(,"tip_mm":[0,0,50])")),
                                 truth_line(2, gtool(0, 10, 10, 0, 10))});
    const auto trace = trace_of({trace_line(0, R"("tools":[)" + ttool(0, 10, 10, 0, -1, -1, "[3,4,50]") + "]"),
                                 trace_line(1, R"("tools":[)" + ttool(0, 10, 10, 0) + "]"),
                                 trace_line(2, R"("tools":[)" + ttool(0, 10, 10, 0, -1, -1, "[0,0,1]") + "]")});
    const ToolScore s = score_tools(truth, trace);
    EXPECT_EQ(s.with_mm, 1);
    EXPECT_DOUBLE_EQ(s.mean_error_mm, 5.0);
    EXPECT_DOUBLE_EQ(s.p95_error_mm, 5.0);
}

TEST(ToolScore, PerFactorLevels) {
    const auto truth = truth_of({
        truth_line(0, gtool(0, 0, 0, 0, 10), R"("factors":{"speed":"0-4","distractors":false})"),
        truth_line(1, gtool(0, 0, 0, 0, 10), R"("factors":{"speed":"0-4","distractors":true})"),
        truth_line(2, gtool(0, 0, 0, 0, 10), R"("factors":{"speed":">8","distractors":true})"),
        truth_line(3, gtool(0, 0, 0, 0, 10), R"("factors":{"speed":">8","distractors":true})"),
    });
    const auto trace = trace_of({trace_line(0, R"("tools":[)" + ttool(0, 3, 4, 0) + "]"),
                                 trace_line(1, R"("tools":[)" + ttool(0, 0, 0, 0) + "]"),
                                 trace_line(2, R"("tools":[)" + ttool(0, 30, 40, 0) + "]"), trace_line(3)});
    const ToolScore s = score_tools(truth, trace);
    ASSERT_EQ(s.levels.size(), 4u);  // map order: (distractors, no), (distractors, yes), (speed, 0-4), (speed, >8)
    EXPECT_EQ(s.levels[0].factor, "distractors");
    EXPECT_EQ(s.levels[0].level, "no");
    EXPECT_EQ(s.levels[0].successes, 1);
    EXPECT_EQ(s.levels[1].tool_frames, 3);
    EXPECT_EQ(s.levels[1].successes, 1);
    EXPECT_EQ(s.levels[1].matched, 2);
    EXPECT_DOUBLE_EQ(s.levels[1].mean_error_px, 25.0);
    EXPECT_EQ(s.levels[2].level, "0-4");
    EXPECT_EQ(s.levels[2].successes, 2);
    EXPECT_DOUBLE_EQ(s.levels[2].mean_error_px, 2.5);
    EXPECT_EQ(s.levels[3].level, ">8");
    EXPECT_EQ(s.levels[3].successes, 0);
    EXPECT_EQ(s.frames_without_trace, 0);
}

TEST(SznitmanScore, HeadWithinHalfScaleAndAxisAsLines) {
    SznitmanAnnotations ann;
    // Head at (x 80, y 50), SCALE 40 (tolerance 20 px), shaft towards +y (90 deg).
    for (int i = 0; i < 4; ++i) ann.frames.push_back({100 + i, 0, {{50, 80, 40, M_PI / 2}}});
    const auto trace = trace_of({
        trace_line(0, R"("tools":[)" + ttool(0, 0, 0, -90, 80, 69) + "]"),   // 19 px, opposite direction: success
        trace_line(1, R"("tools":[)" + ttool(0, 0, 0, 90, 101, 50) + "]"),   // 21 px: fails
        trace_line(2, R"("tools":[)" + ttool(0, 0, 0, 115, 80, 50) + "]"),   // 25 deg: fails
        trace_line(3, R"("tools":[)" + ttool(0, 0, 0, 290, 80, 50) + "," + ttool(1, 0, 0, 0, 300, 300) + "]"),
    });
    const ToolScore s = score_sznitman(ann, trace, 100);
    EXPECT_EQ(s.point, "head");
    EXPECT_EQ(s.tool_frames, 4);
    EXPECT_EQ(s.successes, 2);  // frames 100 and 103 (290 deg is the line at 110, 20 deg off)
    EXPECT_TRUE(s.pairs[0].success);
    EXPECT_TRUE(s.pairs[3].success);
    EXPECT_DOUBLE_EQ(s.pairs[3].axis_error_deg, 20.0);
    EXPECT_EQ(s.false_positives, 1);
    EXPECT_DOUBLE_EQ(s.mean_error_px, (19.0 + 21 + 0 + 0) / 4);
    // Shifted frame numbering: nothing lines up.
    EXPECT_EQ(score_sznitman(ann, trace, 50).matched, 0);
}

TEST(GestureScore, TrialsInTheLayoutOfTable33) {
    const std::string one_og = gtool(0, 0, 0, 0, 10, true, R"(,"gesture":"open_grasper")");
    const std::string one_cs = gtool(0, 0, 0, 0, 10, true, R"(,"gesture":"closed_scissors")");
    const std::string two = gtool(0, 0, 0, 0, 10, true, R"(,"gesture":"open_grasper")") + "," +
                            gtool(1, 9, 9, 0, 10, true, R"(,"gesture":"closed_grasper")");
    std::vector<std::string> gt, tr;
    auto g = [](const char* label, bool fired) {
        return std::string(R"("gesture":{"label":)") + (label ? std::string("\"") + label + "\"" : "null") +
               R"(,"confidence":0.8,"held_ms":500,"fired":)" + (fired ? "true" : "false") + "}";
    };
    // Frames 0-3 open grasper, recognized (fires at 2).
    for (int f = 0; f < 4; ++f) gt.push_back(truth_line(f, one_og));
    tr.push_back(trace_line(0, g(nullptr, false)));
    tr.push_back(trace_line(1, g("open_grasper", false)));
    tr.push_back(trace_line(2, g("open_grasper", true)));
    tr.push_back(trace_line(3, g("open_grasper", false)));
    // Frames 4-6: two tools, no gesture: "none", nothing fires.
    for (int f = 4; f < 7; ++f) {
        gt.push_back(truth_line(f, two));
        tr.push_back(trace_line(f, g(nullptr, false)));
    }
    // Frames 7-9: cross, recognized as triangle.
    for (int f = 7; f < 10; ++f) {
        gt.push_back(truth_line(f, two, R"("gesture":"cross")"));
        tr.push_back(trace_line(f, g("triangle", f == 8)));
    }
    // Frames 10-12: closed scissors, never fires.
    for (int f = 10; f < 13; ++f) {
        gt.push_back(truth_line(f, one_cs));
        tr.push_back(trace_line(f, g("closed_scissors", false)));
    }
    // Frames 13-14: nothing performed, a false trigger; frame 15 has no gesture member.
    for (int f = 13; f < 16; ++f) gt.push_back(truth_line(f, ""));
    tr.push_back(trace_line(13, g(nullptr, false)));
    tr.push_back(trace_line(14, g("open_grasper", true)));
    tr.push_back(trace_line(15));
    const GestureScore s = score_gestures(truth_of(gt), trace_of(tr));
    ASSERT_TRUE(s.present);
    const int og = 0, cs = 3, cross = 4, tri = 5, none = 7;
    EXPECT_EQ(s.trials, 5);
    EXPECT_EQ(s.correct_trials, 2);
    EXPECT_EQ(s.counts[og][og], 1);
    EXPECT_EQ(s.counts[none][none], 1);
    EXPECT_EQ(s.counts[none][og], 1);
    EXPECT_EQ(s.counts[cross][tri], 1);
    EXPECT_EQ(s.counts[cs][none], 1);
    int total = 0;
    for (const auto& row : s.counts)
        for (int n : row) total += n;
    EXPECT_EQ(total, 5);
    EXPECT_DOUBLE_EQ(*s.rate(og), 1.0);
    EXPECT_DOUBLE_EQ(*s.rate(none), 0.5);
    EXPECT_DOUBLE_EQ(*s.rate(cross), 0.0);
    EXPECT_FALSE(s.rate(tri));
    EXPECT_DOUBLE_EQ(*s.overall_rate(), 0.4);
    // Frames with a gesture member: 15; right: 1,2,3 (og) + 4,5,6 (none) + 10,11,12 + 13.
    EXPECT_EQ(s.frames, 15);
    EXPECT_EQ(s.correct_frames, 10);
    EXPECT_FALSE(score_gestures(truth_of(gt), trace_of({trace_line(0)})).present);
}

std::vector<Point2> square(double x, double y, double side) {
    return {{x, y}, {x + side, y}, {x + side, y + side}, {x, y + side}};
}

TEST(RegionScore, ClassesFromOverlapAndCorners) {
    const auto t = square(0, 0, 100);
    const auto same = square(0, 0, 100), s5 = square(5, 0, 100), s30 = square(30, 0, 100),
               s90 = square(90, 0, 100), big = square(0, 0, 200);
    RegionMatch m = classify_region(t, &same);
    EXPECT_EQ(m.cls, RegionClass::kGood);
    EXPECT_DOUBLE_EQ(m.iou, 1.0);
    EXPECT_DOUBLE_EQ(*m.corner_error_px, 0.0);
    m = classify_region(t, &s5);
    EXPECT_EQ(m.cls, RegionClass::kGood);
    EXPECT_NEAR(m.iou, 9500.0 / 10500, 1e-6);
    EXPECT_NEAR(m.coverage, 0.95, 1e-6);
    EXPECT_DOUBLE_EQ(*m.corner_error_px, 5.0);
    m = classify_region(t, &s30);
    EXPECT_EQ(m.cls, RegionClass::kOk);
    EXPECT_NEAR(m.iou, 7000.0 / 13000, 1e-6);
    EXPECT_EQ(classify_region(t, &s90).cls, RegionClass::kFail);
    m = classify_region(t, &big);  // all content, and much more: partial
    EXPECT_EQ(m.cls, RegionClass::kOk);
    EXPECT_NEAR(m.coverage, 1.0, 1e-6);
    EXPECT_NEAR(m.iou, 0.25, 1e-6);
    EXPECT_EQ(classify_region(t, nullptr).cls, RegionClass::kFail);
    // A non-convex (L-shaped) polygon against a convex one: exact by clipping.
    const std::vector<Point2> ell = {{0, 0}, {100, 0}, {100, 50}, {50, 50}, {50, 100}, {0, 100}};
    EXPECT_NEAR(polygon_intersection_area(t, ell), 7500.0, 1e-9);
    EXPECT_NEAR(polygon_intersection_area(square(25, 25, 50), ell), 1875.0, 1e-9);
    EXPECT_DOUBLE_EQ(polygon_area(ell), 7500.0);
    // Both non-convex: rasterised, within 1.5 %. The L and its copy moved by (20, 20)
    // overlap in an L: [20,100]x[20,50] and [20,50]x[20,100], 2400 + 2400 - 900.
    std::vector<Point2> ell2;
    for (const Point2& p : ell) ell2.push_back({p.x + 20, p.y + 20});
    EXPECT_NEAR(polygon_intersection_area(ell, ell2), 3900.0, 3900 * 0.015);
}

TEST(RegionScore, PerFrameClassesAndMeanCornerError) {
    auto poly = [](const std::vector<Point2>& p) {
        std::string s = "[";
        for (std::size_t i = 0; i < p.size(); ++i)
            s += (i ? "," : "") + std::string("[") + std::to_string(p[i].x) + "," + std::to_string(p[i].y) + "]";
        return s + "]";
    };
    const std::string gt_region = R"("regions":[{"id":1,"polygon_px":)" + poly(square(0, 0, 100));
    std::vector<std::string> gt, tr;
    const std::vector<std::vector<Point2>> found = {square(0, 0, 100), square(5, 0, 100), square(30, 0, 100),
                                                    square(90, 0, 100), square(0, 0, 200)};
    for (int f = 0; f < 5; ++f) {
        gt.push_back(truth_line(f, "", gt_region + (f < 2 ? R"(,"change":"translation"}])" : R"(,"change":"zoom_out"}])")));
        tr.push_back(trace_line(f, R"("regions":[{"id":4,"polygon_px":)" + poly(found[f]) + R"(,"state":"tracked","inliers":30}])"));
    }
    gt.push_back(truth_line(5, "", gt_region + R"(,"change":"zoom_out"}])"));
    tr.push_back(trace_line(5, R"("regions":[{"id":1,"polygon_px":)" + poly(square(0, 0, 100)) + R"(,"state":"lost","inliers":0}])"));
    const RegionScore s = score_regions(truth_of(gt), trace_of(tr));
    ASSERT_TRUE(s.present);
    EXPECT_EQ(s.good, 2);
    EXPECT_EQ(s.ok, 2);
    EXPECT_EQ(s.fail, 2);
    EXPECT_EQ(s.with_corners, 5);
    const double big = (0 + 100 + std::sqrt(2.0) * 100 + 100) / 4;
    EXPECT_NEAR(s.mean_corner_error_px, (0 + 5 + 30 + 90 + big) / 5, 1e-9);
    EXPECT_EQ(s.frames[0].trace_id, 4);
    EXPECT_EQ(s.frames[5].trace_id, -1);
    EXPECT_EQ(s.by_change.at("translation"), (std::array<int, 3>{2, 0, 0}));
    EXPECT_EQ(s.by_change.at("zoom_out"), (std::array<int, 3>{0, 2, 2}));
}

}  // namespace
}  // namespace endotower::eval
