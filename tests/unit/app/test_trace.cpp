// The trace format: JSON building, writing atomically, reading back.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "endotower/app/json_line.hpp"
#include "endotower/app/latency_histogram.hpp"
#include "endotower/app/trace_reader.hpp"
#include "endotower/app/trace_writer.hpp"

namespace endotower::app {
namespace {

namespace fs = std::filesystem;

TEST(JsonLine, BuildsNestedObjectsAndArrays) {
    JsonLine j;
    j.clear();
    j.begin_object().field("a", 1).field("b", -2.5).field("c", true).null_field("d");
    j.begin_array("e").value(std::int64_t{1}).value(std::string_view("x")).end_array();
    j.begin_object("f").field("g", "h").end_object();
    j.end_object();
    EXPECT_EQ(j.view(), R"({"a":1,"b":-2.5,"c":true,"d":null,"e":[1,"x"],"f":{"g":"h"}})");
    EXPECT_FALSE(j.overflowed());
}

TEST(JsonLine, EscapesStringsAndWritesNonFiniteAsNull) {
    JsonLine j;
    j.clear();
    j.begin_object().field("s", "q\"b\\n\n\x01").field("nan", std::nan("")).field(
        "inf", std::numeric_limits<double>::infinity());
    j.end_object();
    EXPECT_EQ(j.view(), R"({"s":"q\"b\\n\n\u0001","nan":null,"inf":null})");
}

TEST(JsonLine, DoublesReadBackExactly) {
    JsonLine j;
    j.clear();
    const double v = 0.1 + 0.2;
    j.begin_object().field("v", v).end_object();
    const std::string s(j.view());
    EXPECT_EQ(std::stod(s.substr(5)), v);
}

TEST(JsonLine, OverflowIsReportedNotWrittenPastTheEnd) {
    JsonLine j;
    j.clear();
    j.begin_object();
    const std::string big(1000, 'x');
    for (int i = 0; i < 40; ++i) j.field("k", big);
    EXPECT_TRUE(j.overflowed());
    EXPECT_LE(j.view().size(), JsonLine::kCapacity);
}

TEST(TraceReader, ParsesEveryDocumentedField) {
    const std::string line =
        R"({"frame":7,"seq":9,"capture_ns":100,"present_ns":16766,"latency_ns":16666,"late":false,)"
        R"("stages_us":{"capture_wait":12,"present":800,"analysis":3000},"analysis_age":1,)"
        R"("passthrough":true,"fault":"analysis_threw","input":[{"kind":"press","t_ns":50,"button":0},)"
        R"({"kind":"wheel","t_ns":60,"delta":-3}],"format_change":{"width":1920,"height":1080,)"
        R"("pixel_format":"yuyv"},"status":{"light":0.5}})";
    TraceRecord r;
    std::string err;
    ASSERT_TRUE(parse_trace_line(line, r, err)) << err;
    EXPECT_EQ(r.frame, 7);
    EXPECT_EQ(r.seq, 9);
    EXPECT_EQ(r.capture_ns, 100);
    EXPECT_EQ(r.present_ns, 16766);
    EXPECT_EQ(r.latency_ns, 16666);
    EXPECT_EQ(r.analysis_age, 1);
    EXPECT_TRUE(r.passthrough);
    EXPECT_EQ(r.fault, "analysis_threw");
    ASSERT_EQ(r.input.size(), 2u);
    EXPECT_EQ(r.input[0].button, 0);
    EXPECT_EQ(r.input[1].delta, -3);
    ASSERT_TRUE(r.format_change);
    EXPECT_EQ(r.format_change->width, 1920);
    EXPECT_EQ(r.format_change->pixel_format, "yuyv");
    EXPECT_EQ(r.stages_us.at("analysis"), 3000);
    EXPECT_EQ(r.extra, R"({"status":{"light":0.5}})");
}

TEST(TraceReader, NamesTheBadFieldAndLine) {
    const fs::path p = fs::temp_directory_path() / ("endotower_bad_trace_" + std::to_string(::getpid()) + ".jsonl");
    {
        std::ofstream f(p);
        f << R"({"frame":0,"seq":0,"capture_ns":0,"present_ns":1,"latency_ns":1,"late":false,"passthrough":false})"
          << "\n"
          << R"({"frame":1,"seq":1,"capture_ns":"x","present_ns":1,"latency_ns":1,"late":false,"passthrough":false})"
          << "\n";
    }
    std::vector<TraceRecord> recs;
    std::string err;
    EXPECT_FALSE(read_trace(p.string(), recs, err));
    EXPECT_EQ(err, p.string() + ":2: field 'capture_ns' must be an integer");
    TraceRecord r;
    EXPECT_FALSE(parse_trace_line("{\"frame\":", r, err));
    EXPECT_EQ(err, "not valid JSON");
    EXPECT_FALSE(parse_trace_line(R"({"frame":1})", r, err));
    EXPECT_EQ(err, "missing field 'seq'");
    fs::remove(p);
}

TEST(TraceWriter, WritesAtomicallyAndKeepsTheOldFileOnAbandon) {
    const fs::path dir = fs::temp_directory_path() / ("endotower_trace_writer_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string path = (dir / "t.jsonl").string();
    {
        TraceWriter w;
        ASSERT_TRUE(w.open(path));
        w.write(R"({"a":1})");
        w.write(R"({"a":2})");
        EXPECT_FALSE(fs::exists(path)) << "visible before close";
        ASSERT_TRUE(w.close()) << w.error();
        EXPECT_EQ(w.lines(), 2);
    }
    std::ifstream in(path);
    std::string all((std::istreambuf_iterator<char>(in)), {});
    EXPECT_EQ(all, "{\"a\":1}\n{\"a\":2}\n");
    {
        TraceWriter w;  // destroyed without close(): the old complete file stays
        ASSERT_TRUE(w.open(path));
        w.write(R"({"a":3})");
    }
    std::ifstream again(path);
    std::string kept((std::istreambuf_iterator<char>(again)), {});
    EXPECT_EQ(kept, all);
    EXPECT_FALSE(fs::exists(path + ".tmp"));
    fs::remove_all(dir);
}

TEST(TraceWriter, MissingDirectoryIsNamed) {
    TraceWriter w;
    EXPECT_FALSE(w.open("/nonexistent-dir/t.jsonl"));
    EXPECT_NE(w.error().find("/nonexistent-dir/t.jsonl.tmp"), std::string::npos) << w.error();
}

TEST(TraceWriter, DiskFullIsReportedAndNothingHalfWrittenIsLeft) {
    if (!fs::exists("/dev/full")) GTEST_SKIP() << "/dev/full absent";
    // /dev/full accepts open and fails every write with ENOSPC. Write through a
    // symlink named like a trace so that PATH.tmp is the full device.
    const fs::path dir = fs::temp_directory_path() / ("endotower_trace_full_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    fs::create_symlink("/dev/full", dir / "t.jsonl.tmp");
    TraceWriter w;
    ASSERT_TRUE(w.open((dir / "t.jsonl").string()));
    const std::string line(4096, 'x');
    for (int i = 0; i < 600; ++i) w.write(line);  // > the 1 MiB stdio buffer
    EXPECT_FALSE(w.close());
    EXPECT_NE(w.error().find("No space left on device"), std::string::npos) << w.error();
    EXPECT_FALSE(fs::exists(dir / "t.jsonl"));
    fs::remove_all(dir);
}

TEST(LatencyHistogram, QuantilesWithinOneBin) {
    LatencyHistogram h;
    for (int i = 1; i <= 1000; ++i) h.add(i * 100'000);  // 0.1 .. 100 ms
    EXPECT_EQ(h.count(), 1000);
    EXPECT_EQ(h.min(), 100'000);
    EXPECT_EQ(h.max(), 100'000'000);
    EXPECT_NEAR(h.quantile(0.5), 50'000'000, LatencyHistogram::kBin);
    EXPECT_NEAR(h.quantile(0.99), 99'000'000, LatencyHistogram::kBin);
    EXPECT_EQ(h.quantile(0.0), 100'000);
    EXPECT_EQ(h.quantile(1.0), 100'000'000);
}

TEST(LatencyHistogram, ConstantValueGivesThatValue) {
    LatencyHistogram h;
    for (int i = 0; i < 50; ++i) h.add(16'666'667);
    EXPECT_EQ(h.quantile(0.5), 16'666'667);
    EXPECT_EQ(h.quantile(0.99), 16'666'667);
}

}  // namespace
}  // namespace endotower::app
