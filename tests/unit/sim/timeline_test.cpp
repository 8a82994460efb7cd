#include "endotower/sim/timeline.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "test_util.hpp"

namespace endotower::sim {
namespace {

using Kind = hal::ControlEvent::Kind;
using Anchor = TimelineEntry::Anchor;

TEST(Timeline, ParsesEveryForm) {
    const std::string text =
        "# scripted handle input\n"
        "\n"
        "frame 12   press\n"
        "frame 20   release 0\n"
        "t 1.250    wheel +2\n"
        "   t 2.0\tpress 1   # trailing comment\n"
        "t 0 wheel -1000\n"
        "frame 0 release 7\n"
        "t 3 wheel 1000\n";
    Timeline tl;
    std::string error;
    ASSERT_TRUE(parse_timeline(text, "events.txt", tl, error)) << error;
    ASSERT_EQ(tl.entries.size(), 7u);

    const auto& e = tl.entries;
    EXPECT_EQ(e[0].anchor, Anchor::kFrame);
    EXPECT_EQ(e[0].frame, 12);
    EXPECT_EQ(e[0].event.kind, Kind::kButtonPress);
    EXPECT_EQ(e[0].event.button, 0);
    EXPECT_EQ(e[0].line, 3);

    EXPECT_EQ(e[1].anchor, Anchor::kFrame);
    EXPECT_EQ(e[1].frame, 20);
    EXPECT_EQ(e[1].event.kind, Kind::kButtonRelease);
    EXPECT_EQ(e[1].event.button, 0);
    EXPECT_EQ(e[1].line, 4);

    EXPECT_EQ(e[2].anchor, Anchor::kTime);
    EXPECT_EQ(e[2].offset_ns, 1'250'000'000);
    EXPECT_EQ(e[2].event.kind, Kind::kWheel);
    EXPECT_EQ(e[2].event.delta, 2);
    EXPECT_EQ(e[2].line, 5);

    EXPECT_EQ(e[3].anchor, Anchor::kTime);
    EXPECT_EQ(e[3].offset_ns, 2 * hal::kSecond);
    EXPECT_EQ(e[3].event.kind, Kind::kButtonPress);
    EXPECT_EQ(e[3].event.button, 1);
    EXPECT_EQ(e[3].line, 6);

    EXPECT_EQ(e[4].offset_ns, 0);
    EXPECT_EQ(e[4].event.delta, -1000);
    EXPECT_EQ(e[5].frame, 0);
    EXPECT_EQ(e[5].event.kind, Kind::kButtonRelease);
    EXPECT_EQ(e[5].event.button, 7);
    EXPECT_EQ(e[6].offset_ns, 3 * hal::kSecond);
    EXPECT_EQ(e[6].event.delta, 1000);
    for (const auto& entry : e) EXPECT_EQ(entry.event.time_ns, 0);  // filled when scheduled
}

TEST(Timeline, FractionalSecondsAreExactNanoseconds) {
    Timeline tl;
    std::string error;
    ASSERT_TRUE(
        parse_timeline("t 0.1 press\nt 0.000000001 press\nt 12.345678901 press\n", "x", tl, error))
        << error;
    ASSERT_EQ(tl.entries.size(), 3u);
    EXPECT_EQ(tl.entries[0].offset_ns, 100'000'000);
    EXPECT_EQ(tl.entries[1].offset_ns, 1);
    EXPECT_EQ(tl.entries[2].offset_ns, 12'345'678'901);
}

TEST(Timeline, CrlfAndMissingFinalNewline) {
    Timeline tl;
    std::string error;
    ASSERT_TRUE(parse_timeline("# dos\r\nframe 1 press\r\n\r\nframe 2 release\r\nt 1 wheel -3",
                               "dos.txt", tl, error))
        << error;
    ASSERT_EQ(tl.entries.size(), 3u);
    EXPECT_EQ(tl.entries[0].line, 2);
    EXPECT_EQ(tl.entries[1].line, 4);
    EXPECT_EQ(tl.entries[2].line, 5);
    EXPECT_EQ(tl.entries[2].event.delta, -3);
}

TEST(Timeline, EmptyAndCommentOnlyTextsGiveNoEntries) {
    Timeline tl;
    std::string error;
    EXPECT_TRUE(parse_timeline("", "a", tl, error));
    EXPECT_TRUE(tl.entries.empty());
    EXPECT_TRUE(parse_timeline("# nothing\n\n   \n\t# more\n", "a", tl, error));
    EXPECT_TRUE(tl.entries.empty());
}

struct BadLine {
    std::string line;
    std::string message;  // after "events.txt:3: "
};

// Names the case by its bad line in test listings and failure messages.
void PrintTo(const BadLine& b, std::ostream* os) {
    *os << b.line;
}

class TimelineErrors : public ::testing::TestWithParam<BadLine> {};

TEST_P(TimelineErrors, NameFileLineAndField) {
    // Two good lines and a comment before the bad one: it is line 4.
    const std::string text = "frame 1 press\n# ok\nt 0.5 release\n" + GetParam().line + "\n";
    Timeline tl;
    std::string error;
    EXPECT_FALSE(parse_timeline(text, "events.txt", tl, error));
    EXPECT_EQ(error, "events.txt:4: " + GetParam().message);
    EXPECT_TRUE(tl.entries.empty());
}

INSTANTIATE_TEST_SUITE_P(
    Messages, TimelineErrors,
    ::testing::Values(
        BadLine{"frame 3 presss", "unknown event 'presss' (expected press, release, wheel or region)"},
        BadLine{"frame -2 press", "frame index '-2' must be a non-negative integer"},
        BadLine{"frame 12x press", "frame index '12x' must be a non-negative integer"},
        BadLine{"frame 1.5 press", "frame index '1.5' must be a non-negative integer"},
        BadLine{"frame 99999999999999999999 press",
                "frame index '99999999999999999999' must be a non-negative integer"},
        BadLine{"frame", "'frame' needs a frame index (non-negative integer)"},
        BadLine{"t -1 press", "time '-1' must be a number of seconds >= 0 (like 1.250)"},
        BadLine{"t abc press", "time 'abc' must be a number of seconds >= 0 (like 1.250)"},
        BadLine{"t 1e3 press", "time '1e3' must be a number of seconds >= 0 (like 1.250)"},
        BadLine{"t nan press", "time 'nan' must be a number of seconds >= 0 (like 1.250)"},
        BadLine{"t 1.2.3 press", "time '1.2.3' must be a number of seconds >= 0 (like 1.250)"},
        BadLine{"t", "'t' needs a time in seconds (number >= 0)"},
        BadLine{"at 3 press", "unknown anchor 'at' (expected 'frame N' or 't SECONDS')"},
        BadLine{"frame 3", "missing event after frame 3 (expected press, release, wheel or region)"},
        BadLine{"t 1.5   # later", "missing event after t 1.5 (expected press, release, wheel or region)"},
        BadLine{"frame 3 wheel x",
                "wheel delta must be a non-zero integer in -1000..1000, got 'x'"},
        BadLine{"frame 3 wheel 0",
                "wheel delta must be a non-zero integer in -1000..1000, got '0'"},
        BadLine{"frame 3 wheel 1001",
                "wheel delta must be a non-zero integer in -1000..1000, got '1001'"},
        BadLine{"frame 3 wheel -1001",
                "wheel delta must be a non-zero integer in -1000..1000, got '-1001'"},
        BadLine{"frame 3 wheel 2.5",
                "wheel delta must be a non-zero integer in -1000..1000, got '2.5'"},
        BadLine{"frame 3 wheel +-2",
                "wheel delta must be a non-zero integer in -1000..1000, got '+-2'"},
        BadLine{"frame 3 wheel", "wheel needs a delta (non-zero integer in -1000..1000)"},
        BadLine{"frame 3 press 8", "button '8' must be an integer in 0..7"},
        BadLine{"frame 3 release -1", "button '-1' must be an integer in 0..7"},
        BadLine{"frame 3 press one", "button 'one' must be an integer in 0..7"},
        BadLine{"frame 3 press 1 2", "unexpected '2' after the event"},
        BadLine{"frame 3 wheel 2 extra", "unexpected 'extra' after the event"},
        BadLine{"frame 3 release 0 0", "unexpected '0' after the event"},
        BadLine{"frame 3 region 1,2 3,4", "a region needs at least 3 vertices \"x1,y1 x2,y2 x3,y3\", got 2"},
        BadLine{"frame 3 region", "a region needs at least 3 vertices \"x1,y1 x2,y2 x3,y3\", got 0"},
        BadLine{"frame 3 region 1,2 3,4 5", "region vertex '5' must be x,y (two numbers)"},
        BadLine{"frame 3 region 1,2 3,4 5,y", "region vertex '5,y' must be x,y (two numbers)"},
        BadLine{"frame 3 region 1,2 3,4 nan,1", "region vertex 'nan,1' must be x,y (two numbers)"},
        BadLine{"frame 3 region 1,2 3,4 1e3,1", "region vertex '1e3,1' must be x,y (two numbers)"},
        BadLine{"t 1 region 0,0 1,0 2,0 3,0 4,0 5,0 6,0 7,0 8,0 9,0 10,0 11,0 12,0 13,0 14,0 15,0 16,0",
                "a region has at most 16 vertices"},
        BadLine{"frame 3 region 1,2 3,4 5,6 overlay=object:cube 7,8",
                "overlay=KIND must come after the region's vertices"},
        BadLine{"frame 3 region 1,2 3,4 overlay=markers",
                "a region needs at least 3 vertices \"x1,y1 x2,y2 x3,y3\", got 2"}));

TEST(Timeline, RegionOverlayIsKeptAsWritten) {
    Timeline tl;
    std::string error;
    ASSERT_TRUE(parse_timeline("frame 3 region 1,2 30,4 5,60 overlay=image:ct/a.png\n"
                               "frame 4 region 1,2 30,4 5,60\n",
                               "e.txt", tl, error))
        << error;
    ASSERT_EQ(tl.entries.size(), 2u);
    EXPECT_EQ(tl.entries[0].region.size(), 3u);
    EXPECT_EQ(tl.entries[0].overlay, "image:ct/a.png");
    EXPECT_EQ(tl.entries[1].overlay, "");
}

TEST(Timeline, RegionMarksCarryTheirPolygonAndAreNotHandleEvents) {
    Timeline tl;
    std::string error;
    ASSERT_TRUE(parse_timeline("frame 2 press\nframe 30 region 100,80 220.5,84 -3,+190\n", "e.txt", tl, error))
        << error;
    ASSERT_EQ(tl.entries.size(), 2u);
    EXPECT_TRUE(tl.entries[0].region.empty());
    const TimelineEntry& r = tl.entries[1];
    EXPECT_EQ(r.frame, 30);
    EXPECT_EQ(r.line, 2);
    ASSERT_EQ(r.region.size(), 3u);
    EXPECT_EQ(r.region[1].x, 220.5);
    EXPECT_EQ(r.region[1].y, 84.0);
    EXPECT_EQ(r.region[2].x, -3.0);
    EXPECT_EQ(r.region[2].y, 190.0);
}

TEST(Timeline, ErrorLineCountsCrlfBlankAndCommentLines) {
    Timeline tl;
    std::string error;
    EXPECT_FALSE(
        parse_timeline("\r\n# a\r\n\r\nframe 1 press\r\nframe 2 presss\r\n", "dos.txt", tl, error));
    EXPECT_EQ(error, "dos.txt:5: unknown event 'presss' (expected press, release, wheel or region)");
}

TEST(Timeline, LoadsAFileAndNamesItInMessages) {
    test::TempDir dir("timeline");
    const std::string good = dir.file("good.txt");
    std::ofstream(good) << "frame 4 press\nt 0.25 wheel -1\n";
    Timeline tl;
    std::string error;
    ASSERT_TRUE(load_timeline(good, tl, error)) << error;
    ASSERT_EQ(tl.entries.size(), 2u);
    EXPECT_EQ(tl.entries[0].frame, 4);
    EXPECT_EQ(tl.entries[1].offset_ns, 250'000'000);
    EXPECT_EQ(tl.entries[1].event.delta, -1);

    const std::string bad = dir.file("bad.txt");
    std::ofstream(bad) << "frame 4 press\n\nframe 5 wheel 0\n";
    EXPECT_FALSE(load_timeline(bad, tl, error));
    EXPECT_EQ(error, bad + ":3: wheel delta must be a non-zero integer in -1000..1000, got '0'");
}

TEST(Timeline, MissingFileNamesThePath) {
    test::TempDir dir("timeline");
    const std::string path = dir.file("absent.txt");
    Timeline tl;
    std::string error;
    EXPECT_FALSE(load_timeline(path, tl, error));
    EXPECT_EQ(error,
              "cannot read timeline: open(" + path + "): No such file or directory (errno 2)");
}

TEST(Timeline, DirectoryIsNotATimeline) {
    test::TempDir dir("timeline");
    Timeline tl;
    std::string error;
    EXPECT_FALSE(load_timeline(dir.path().string(), tl, error));
    EXPECT_EQ(error,
              "cannot read timeline: read(" + dir.path().string() + "): Is a directory (errno 21)");
}

}  // namespace
}  // namespace endotower::sim
