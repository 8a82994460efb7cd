// `endotower eval` end to end: summary, report files, exit codes.
#include <sys/wait.h>

#include <array>
#include <fstream>
#include <sstream>

#include "eval_test_util.hpp"

namespace endotower::eval {
namespace {

using namespace test;


std::string read_file(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// Ten frames of one tool, 10 px wide; the trace is 3-4-5 px off on frames 0-8 and
// 30 px off on frame 9: 9 of 10 within the rule, mean error 7.5 px.
struct Fixture {
    fs::path dir, truth, trace;
};
Fixture make_fixture(const std::string& name) {
    Fixture f;
    f.dir = temp_dir(name);
    std::vector<std::string> gt, tr;
    for (int i = 0; i < 10; ++i) {
        gt.push_back(truth_line(i, gtool(0, 100 + i, 200, 45, 10),
                                i < 5 ? R"("factors":{"speed":"0-4"})" : R"("factors":{"speed":"4-8"})"));
        const double dx = i < 9 ? 3 : 18, dy = i < 9 ? 4 : 24;
        tr.push_back(trace_line(i, R"("tools":[)" + ttool(1, 100 + i + dx, 200 + dy, 40) + "]"));
    }
    f.truth = write_lines(f.dir / "truth.jsonl", gt);
    f.trace = write_lines(f.dir / "trace.jsonl", tr);
    return f;
}

TEST(EvalCommand, PassingThresholdsWriteTheReport) {
    const Fixture f = make_fixture("cli_pass");
    const fs::path report = f.dir / "report";
    const CommandRun r = run_eval("--trace " + f.trace.string() + " --truth " + f.truth.string() + " --report " +
                           report.string() + " --min-success 0.9 --max-tip-error 7.5 --max-false-positives 0");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("success 90.0 % (9/10)"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("tip error mean 7.50 px, p95 30.00 px over 10 matched"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("threshold: success rate 90.0 % >= 90.0 % PASS"), std::string::npos) << r.output;
    const std::string md = read_file(report / "report.md");
    EXPECT_NE(md.find("| Tool speed (cm/s) | 0-4 | 100.0 | 5 | 5.00 |"), std::string::npos) << md;
    EXPECT_NE(md.find("|  | 4-8 | 80.0 | 5 | 10.00 |"), std::string::npos) << md;
    EXPECT_NE(md.find("| tool 0 | 90.0% (9/10) |"), std::string::npos) << md;
    EXPECT_NE(md.find("## Thresholds: PASS"), std::string::npos) << md;
    for (const char* png : {"tip_error.png", "success_by_factor.png"}) {
        const std::string bytes = read_file(report / png);
        ASSERT_GT(bytes.size(), 8u) << png;
        EXPECT_EQ(bytes.substr(1, 3), "PNG") << png;
    }
    EXPECT_FALSE(fs::exists(report / "gesture_confusion.png"));  // the trace has no gestures
    // Again over the old report: replaced whole, nothing left beside it.
    EXPECT_EQ(run_eval("--trace " + f.trace.string() + " --truth " + f.truth.string() + " --report " + report.string()).status, 0);
    int entries = 0;
    for (const auto& e : fs::directory_iterator(f.dir)) entries += e.path().filename().string().rfind("report", 0) == 0;
    EXPECT_EQ(entries, 1);
    EXPECT_EQ(read_file(report / "report.md").find("## Thresholds"), std::string::npos);
}

TEST(EvalCommand, FailingThresholdExitsOne) {
    const Fixture f = make_fixture("cli_fail");
    CommandRun r = run_eval("--trace " + f.trace.string() + " --truth " + f.truth.string() + " --min-success 0.95");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("threshold: success rate 90.0 % >= 95.0 % FAIL"), std::string::npos) << r.output;
    r = run_eval("--trace " + f.trace.string() + " --truth " + f.truth.string() + " --max-tip-error 7.4");
    EXPECT_EQ(r.status, 1) << r.output;
    // A threshold on a metric the data cannot give fails too.
    r = run_eval("--trace " + f.trace.string() + " --truth " + f.truth.string() + " --max-tip-error-mm 5");
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("mean 3-D tip error (mm) n/a <= 5.000 FAIL"), std::string::npos) << r.output;
}

TEST(EvalCommand, MalformedInputExitsTwoWithFileAndLine) {
    const Fixture f = make_fixture("cli_bad");
    const fs::path bad = f.dir / "bad.jsonl";
    write_lines(bad, {trace_line(0), trace_line(1, R"("tools":[{"id":0,"tip_px":"x"}])")});
    CommandRun r = run_eval("--trace " + bad.string() + " --truth " + f.truth.string());
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.output, "endotower eval: " + bad.string() + ":2: field 'tools[0].tip_px' must be [x, y] (two numbers)\n");
    r = run_eval("--trace " + f.trace.string() + " --truth " + f.trace.string());
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.output, "endotower eval: " + f.trace.string() + ":1: missing field 'tools[0].visible'\n");
    EXPECT_EQ(run_eval("--trace " + f.trace.string()).status, 2);
    EXPECT_EQ(run_eval("--trace " + f.trace.string() + " --truth a --sznitman b").status, 2);
    EXPECT_EQ(run_eval("--trace " + f.trace.string() + " --truth " + f.truth.string() + " --min-success 2").status, 2);
    EXPECT_EQ(run_eval("--trace " + (f.dir / "missing.jsonl").string() + " --truth " + f.truth.string()).output,
              "endotower eval: cannot read trace: " + (f.dir / "missing.jsonl").string() + "\n");
}

TEST(EvalCommand, SznitmanAnnotationsEndToEnd) {
    const fs::path d = temp_dir("cli_sz");
    std::ofstream(d / "a.xml") << "<?xml version='1.0'?>\n<tagDocument>\n<numberOfFrames>\n2\n</numberOfFrames>\n"
                                  "<frame>\n<PositionIndex> 7 </PositionIndex>\n<tool> 50 80 40 1.5707963 </tool>\n</frame>\n"
                                  "<frame>\n<PositionIndex> 8 </PositionIndex>\n<tool> 50 80 40 1.5707963 </tool>\n</frame>\n"
                                  "</tagDocument>\n";
    const std::string trace = write_lines(d / "t.jsonl", {trace_line(0, R"("tools":[)" + ttool(0, 0, 0, -90, 80, 60) + "]"),
                                                          trace_line(1, R"("tools":[)" + ttool(0, 0, 0, 90, 80, 75) + "]")});
    const CommandRun r = run_eval("--trace " + trace + " --sznitman " + (d / "a.xml").string() + " --min-success 0.5");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("success 50.0 % (1/2); head error mean 17.50 px"), std::string::npos) << r.output;
    EXPECT_EQ(run_eval("--trace " + trace + " --sznitman " + (d / "a.xml").string() + " --first-index 6 --min-success 0.5").status, 1);
}

}  // namespace
}  // namespace endotower::eval
