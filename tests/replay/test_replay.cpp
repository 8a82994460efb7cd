// End-to-end: the `endotower sim` command on recordings, checked frame by frame.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "endotower/app/trace_reader.hpp"
#include "endotower_command.hpp"
#include "scratch_dir.hpp"

namespace {

namespace fs = std::filesystem;

using CommandResult = endotower::test::CommandRun;
CommandResult run(const std::string& args) {
    return endotower::test::run_endotower(args);
}

fs::path fresh_dir(const std::string& name) {
    // Per process: several checkouts may run the suite at once on one machine.
    return endotower::test::scratch_dir("replay_" + name);
}

// Numbered PNG frames with distinct, textured content (a gradient that moves).
void write_frames(const fs::path& dir, int n, int w, int h) {
    fs::create_directories(dir);
    for (int i = 0; i < n; ++i) {
        cv::Mat m(h, w, CV_8UC3);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                m.at<cv::Vec3b>(y, x) =
                    cv::Vec3b(static_cast<uchar>(x + i), static_cast<uchar>(y * 2 + i),
                              static_cast<uchar>((x ^ y) + 3 * i));
        cv::imwrite((dir / (std::to_string(i) + ".png")).string(), m);
    }
}

// Bounding box of the pixels that differ (empty if none).
cv::Rect diff_box(const cv::Mat& a, const cv::Mat& b) {
    int x0 = a.cols, y0 = a.rows, x1 = -1, y1 = -1;
    for (int y = 0; y < a.rows; ++y)
        for (int x = 0; x < a.cols; ++x)
            if (a.at<cv::Vec3b>(y, x) != b.at<cv::Vec3b>(y, x)) {
                x0 = std::min(x0, x), y0 = std::min(y0, y);
                x1 = std::max(x1, x), y1 = std::max(y1, y);
            }
    return x1 < 0 ? cv::Rect() : cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
}

std::vector<endotower::app::TraceRecord> load(const fs::path& p) {
    std::vector<endotower::app::TraceRecord> recs;
    std::string err;
    EXPECT_TRUE(endotower::app::read_trace(p.string(), recs, err)) << err;
    return recs;
}

const std::string kBoard =
    std::string("sim --board ") + ENDOTOWER_SOURCE_DIR + "/board/sim/board.yaml ";

// The shipped board without the tool tracker: only the status badge draws, so the
// rest of the picture must pass through untouched.
std::string badge_only_board(const fs::path& dir) {
    std::ofstream(dir / "badge.yaml")
        << "board: t\nanalysis: {stage: status_badge, tracker: none}\n";
    return "sim --board " + (dir / "badge.yaml").string() + " ";
}

TEST(Replay, EveryFrameOutInOrderWithTheConfiguredLatencyAndExactPassthrough) {
    const fs::path d = fresh_dir("order");
    write_frames(d / "in", 40, 640, 480);
    const CommandResult r = run(badge_only_board(d) + "--input " + (d / "in").string() +
                                " --frames " + (d / "out").string() + " --trace " +
                                (d / "trace.jsonl").string() + " --latency-ms 50 --out ''");
    ASSERT_EQ(r.status, 0) << r.output;
    const auto recs = load(d / "trace.jsonl");
    ASSERT_EQ(recs.size(), 40u);
    for (int i = 0; i < 40; ++i) {
        const auto& t = recs[static_cast<std::size_t>(i)];
        EXPECT_EQ(t.frame, i);
        EXPECT_EQ(t.seq, i);
        EXPECT_EQ(t.latency_ns, 50'000'000) << i;
        EXPECT_EQ(t.present_ns - t.capture_ns, 50'000'000) << i;
        EXPECT_FALSE(t.late);
        if (i > 0) {
            EXPECT_EQ(t.capture_ns - recs[static_cast<std::size_t>(i - 1)].capture_ns, 40000000);
        }
        // Output frame i is input frame i, bit for bit, outside the corner badge.
        const cv::Mat in = cv::imread((d / "in" / (std::to_string(i) + ".png")).string());
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", i);
        const cv::Mat out = cv::imread((d / "out" / name).string());
        ASSERT_EQ(out.size(), in.size()) << name;
        const cv::Rect changed = diff_box(in, out);
        // Only the badge in the top-left corner may differ.
        EXPECT_LE(changed.x + changed.width, in.cols / 2) << name;
        EXPECT_LE(changed.y + changed.height, in.rows / 4) << name;
    }
}

TEST(Replay, WithoutAnalysisTheOutputIsTheInputBitForBit) {
    const fs::path d = fresh_dir("exact");
    write_frames(d / "in", 10, 160, 120);
    std::ofstream(d / "board.yaml") << "board: t\nanalysis: {stage: none}\n";
    const CommandResult r =
        run("sim --board " + (d / "board.yaml").string() + " --input " + (d / "in").string() +
            " --frames " + (d / "out").string() + " --out " + (d / "out.mkv").string());
    ASSERT_EQ(r.status, 0) << r.output;
    cv::VideoCapture cap((d / "out.mkv").string());
    for (int i = 0; i < 10; ++i) {
        const cv::Mat in = cv::imread((d / "in" / (std::to_string(i) + ".png")).string());
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", i);
        const cv::Mat out = cv::imread((d / "out" / name).string());
        EXPECT_EQ(cv::norm(in, out, cv::NORM_INF), 0.0) << name;
        cv::Mat video;
        ASSERT_TRUE(cap.read(video)) << "video frame " << i;
        EXPECT_EQ(cv::norm(in, video, cv::NORM_INF), 0.0) << "FFV1 is lossless, frame " << i;
    }
}

TEST(Replay, DeterministicReplayIsIdenticalRunToRun) {
    const fs::path d = fresh_dir("determinism");
    std::string traces[2];
    for (int k = 0; k < 2; ++k) {
        const fs::path o = d / std::to_string(k);
        const CommandResult r = run(kBoard + "--frames " + o.string() + " --trace " +
                                    (o / "t.jsonl").string() + " --out ''");
        ASSERT_EQ(r.status, 0) << r.output;
        // Wall-clock stage timings are measurements; everything else must match.
        for (auto& t : load(o / "t.jsonl"))
            traces[k] += std::to_string(t.frame) + " " + std::to_string(t.capture_ns) + " " +
                         std::to_string(t.present_ns) + " " +
                         std::to_string(t.analysis_age.value_or(-1)) + " " +
                         std::to_string(t.input.size()) + " " + t.extra + "\n";
    }
    EXPECT_EQ(traces[0], traces[1]);
    int frames = 0;
    for (const auto& e : fs::directory_iterator(d / "0")) {
        if (e.path().extension() != ".png") continue;
        ++frames;
        std::ifstream a(e.path(), std::ios::binary),
            b(d / "1" / e.path().filename(), std::ios::binary);
        const std::string sa((std::istreambuf_iterator<char>(a)), {}),
            sb((std::istreambuf_iterator<char>(b)), {});
        ASSERT_EQ(sa, sb) << e.path().filename();
    }
    EXPECT_EQ(frames, 180);
}

TEST(Replay, BundledRecordingWithTimeline) {
    const fs::path d = fresh_dir("bundled");
    const CommandResult r =
        run(kBoard + "--out " + (d / "out.mkv").string() + " --trace " + (d / "t.jsonl").string());
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("180 frames in, 180 out, 0 late"), std::string::npos) << r.output;
    EXPECT_NE(
        r.output.find("target 33.333 ms; min 33.333, median 33.333, p99 33.333, max 33.333 ms"),
        std::string::npos)
        << r.output;
    const auto recs = load(d / "t.jsonl");
    ASSERT_EQ(recs.size(), 180u);
    // board/sim/events.txt: press at frame 30, release at 45, wheel at t=2.0 s (frame 60).
    ASSERT_EQ(recs[30].input.size(), 1u);
    EXPECT_EQ(recs[30].input[0].kind, "press");
    ASSERT_EQ(recs[45].input.size(), 1u);
    EXPECT_EQ(recs[45].input[0].kind, "release");
    ASSERT_EQ(recs[60].input.size(), 1u);
    EXPECT_EQ(recs[60].input[0].delta, 1);
    EXPECT_NE(recs[40].extra.find("\"button_down\":true"), std::string::npos) << recs[40].extra;
    EXPECT_NE(recs[50].extra.find("\"button_down\":false"), std::string::npos) << recs[50].extra;
    cv::VideoCapture cap((d / "out.mkv").string());
    ASSERT_TRUE(cap.isOpened());
    EXPECT_EQ(static_cast<int>(cap.get(cv::CAP_PROP_FRAME_WIDTH)), 640);
    int n = 0;
    cv::Mat m;
    while (cap.read(m)) ++n;
    EXPECT_EQ(n, 180);
    EXPECT_FALSE(fs::exists(d / "t.jsonl.tmp"));
}

TEST(Replay, TruncatedRecordingStillYieldsValidOutputs) {
    const fs::path d = fresh_dir("truncated");
    {
        cv::VideoWriter w((d / "in.avi").string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                          {320, 240});
        ASSERT_TRUE(w.isOpened());
        for (int i = 0; i < 60; ++i)
            w.write(cv::Mat(240, 320, CV_8UC3, cv::Scalar(i * 4, 100, 200 - i * 3)));
    }
    fs::resize_file(d / "in.avi", fs::file_size(d / "in.avi") / 2);
    const CommandResult r =
        run(kBoard + "--input " + (d / "in.avi").string() + " --out " + (d / "out.mkv").string() +
            " --trace " + (d / "t.jsonl").string() + " --events ''");
    ASSERT_EQ(r.status, 0) << r.output;
    const auto recs = load(d / "t.jsonl");
    EXPECT_GT(recs.size(), 10u);
    EXPECT_LT(recs.size(), 60u);
    cv::VideoCapture cap((d / "out.mkv").string());
    int n = 0;
    cv::Mat m;
    while (cap.read(m)) ++n;
    EXPECT_EQ(static_cast<std::size_t>(n), recs.size());
}

TEST(Replay, SizeChangeMidStreamKeepsEveryFrameAndStartsANewSegment) {
    const fs::path d = fresh_dir("size_change");
    write_frames(d / "in", 12, 320, 240);
    // Frames 12..19 at another size, numbered after the first ones.
    const fs::path big = d / "big";
    write_frames(big, 8, 480, 360);
    for (int i = 0; i < 8; ++i)
        fs::rename(big / (std::to_string(i) + ".png"),
                   d / "in" / (std::to_string(12 + i) + ".png"));
    const CommandResult r =
        run(kBoard + "--input " + (d / "in").string() + " --out " + (d / "out.mkv").string() +
            " --trace " + (d / "t.jsonl").string() + " --events ''");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("1 format changes"), std::string::npos) << r.output;
    const auto recs = load(d / "t.jsonl");
    ASSERT_EQ(recs.size(), 20u);
    for (const auto& t : recs) {
        EXPECT_EQ(t.format_change.has_value(), t.frame == 12) << t.frame;
        EXPECT_EQ(t.latency_ns, 40'000'000) << t.frame;
    }
    EXPECT_EQ(recs[12].format_change->width, 480);
    EXPECT_EQ(recs[12].format_change->height, 360);
    // The file sink starts a new segment at the change: out.mkv then out.1.mkv.
    cv::VideoCapture a((d / "out.mkv").string()), b((d / "out.1.mkv").string());
    ASSERT_TRUE(a.isOpened());
    ASSERT_TRUE(b.isOpened());
    EXPECT_EQ(a.get(cv::CAP_PROP_FRAME_WIDTH), 320);
    EXPECT_EQ(b.get(cv::CAP_PROP_FRAME_WIDTH), 480);
    int na = 0, nb = 0;
    cv::Mat m;
    while (a.read(m)) ++na;
    while (b.read(m)) ++nb;
    EXPECT_EQ(na, 12);
    EXPECT_EQ(nb, 8);
}

TEST(Replay, RealLaparoscopicClip) {
    const fs::path frames = fs::path(ENDOTOWER_SHARED_DATA) / "sznitman_lap" / "frames";
    if (!fs::is_directory(frames)) GTEST_SKIP() << "skipped: " << frames << " is absent";
    const fs::path d = fresh_dir("sznitman");
    const CommandResult r =
        run(badge_only_board(d) + "--input " + frames.string() + " --out '' --frames " +
            (d / "out").string() + " --trace " + (d / "t.jsonl").string() + " --events ''");
    ASSERT_EQ(r.status, 0) << r.output;
    const auto recs = load(d / "t.jsonl");
    ASSERT_EQ(recs.size(), 400u);
    for (std::size_t i = 0; i < recs.size(); ++i) {
        EXPECT_EQ(recs[i].frame, static_cast<std::int64_t>(i));
        EXPECT_EQ(recs[i].latency_ns, 40'000'000);  // one period at 25 fps
    }
    // Frame 001175.png is the first: output 000000.png shows it outside the badge.
    const cv::Mat in = cv::imread((frames / "001175.png").string());
    const cv::Mat out = cv::imread((d / "out" / "000000.png").string());
    const cv::Rect lower(0, in.rows / 4, in.cols, in.rows - in.rows / 4);
    EXPECT_EQ(cv::norm(in(lower), out(lower), cv::NORM_INF), 0.0);
}

// The default board's tool tracker (the learned likelihood tracker, with the shipped
// model) on a simulator suite the model never saw (the suite's own seed; the model
// trains on seed 9001): success by the book's rule at least the goal for
// speed 0-4 cm/s (97 %; the book measured 82 %), through `scene`, `sim` and `eval`.
TEST(Replay, DefaultTrackerMeetsTheGoalOnAnUnseenSimulatorSuite) {
    const fs::path d = fresh_dir("tracking");
    CommandResult r =
        run(std::string("scene --scenario ") + ENDOTOWER_SOURCE_DIR +
            "/board/sim/scenarios/t41_speed_0_4.yaml --frames 30 --out " + (d / "scene").string());
    ASSERT_EQ(r.status, 0) << r.output;
    r = run(kBoard + "--input " + (d / "scene" / "frames").string() +
            " --events '' --out '' --frames " + (d / "out").string() + " --trace " +
            (d / "t.jsonl").string());
    ASSERT_EQ(r.status, 0) << r.output;
    r = run("eval --trace " + (d / "t.jsonl").string() + " --truth " +
            (d / "scene" / "truth.jsonl").string() +
            " --min-success 0.97 --max-false-positives 0.05");
    EXPECT_EQ(r.status, 0) << r.output;
}

// With a calibration of the simulated scope (its exact intrinsics and distortion,
// as OpenCV's pinhole model), every tool gets a 3-D tip. The goal: <= 3 mm
// mean at 30-70 mm; `pose_depth_30_70` moves the tip from 35 to 65 mm in these 30
// frames (measured 1.7 mm mean over its 50, docs/tracking.md).
TEST(Replay, CalibratedScopeGivesTheToolTipInMillimetres) {
    const fs::path d = fresh_dir("pose");
    CommandResult r = run(std::string("scene --scenario ") + ENDOTOWER_SOURCE_DIR +
                          "/board/sim/scenarios/pose_depth_30_70.yaml --frames 30 --out " +
                          (d / "scene").string());
    ASSERT_EQ(r.status, 0) << r.output;
    std::ifstream truth(d / "scene" / "truth.jsonl");
    std::string line;
    ASSERT_TRUE(std::getline(truth, line));
    const nlohmann::json cam = nlohmann::json::parse(line)["camera"];
    const double fx = cam["fx"], fy = cam["fy"], f2 = fx * fy;
    const double k1 = cam["distortion"]["k"][0], k2 = cam["distortion"]["k"][1];
    // The simulator's odd polynomial is in px about (cx, cy); OpenCV's in focal lengths.
    nlohmann::json cal = {{"scope", "sim"},
                          {"model", "pinhole"},
                          {"image_size", {cam["width"], cam["height"]}},
                          {"fx", fx},
                          {"fy", fy},
                          {"cx", cam["cx"]},
                          {"cy", cam["cy"]},
                          {"distortion", {k1 * f2, k2 * f2 * f2, 0, 0, 0}},
                          {"rms", 0.1}};
    std::ofstream(d / "cal.json") << cal.dump(1) << "\n";
    std::ofstream(d / "board.yaml")
        << "board: t\ncalibration: cal.json\nanalysis: {stage: none, tracker: likelihood, "
           "tool_model: "
        << ENDOTOWER_SOURCE_DIR
        << "/board/sim/models/tool_likelihood.bin, "
           "tool_diameter_mm: 5}\n";
    r = run("sim --board " + (d / "board.yaml").string() + " --input " +
            (d / "scene" / "frames").string() + " --events '' --out '' --frames " +
            (d / "out").string() + " --trace " + (d / "t.jsonl").string());
    ASSERT_EQ(r.status, 0) << r.output;
    r = run("eval --trace " + (d / "t.jsonl").string() + " --truth " +
            (d / "scene" / "truth.jsonl").string() + " --min-success 0.97 --max-tip-error-mm 3");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("3-D tip error mean"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("(30)"), std::string::npos)
        << "every frame has a 3-D tip: " << r.output;
}

TEST(Cli, HelpAndVersion) {
    CommandResult r = run("--help");
    EXPECT_EQ(r.status, 0);
    EXPECT_NE(r.output.find("sim"), std::string::npos);
    r = run("--version");
    EXPECT_EQ(r.status, 0);
    EXPECT_EQ(r.output.rfind("endotower ", 0), 0u) << r.output;
    r = run("sim --help");
    EXPECT_EQ(r.status, 0);
    EXPECT_NE(r.output.find("--realtime"), std::string::npos);
}

struct BadInput {
    std::string args;
    std::string message;
};

TEST(Cli, BadInputIsNamedWithExitCode2) {
    const fs::path d = fresh_dir("cli");
    fs::create_directories(d / "empty");
    std::ofstream(d / "notavideo.mp4") << "this is text, not a video\n";
    std::ofstream(d / "events.txt") << "frame 1 press\nframe 2 presss\n";
    std::ofstream(d / "board.yaml") << "board: x\nvideo:\n  latency_ms: soon\n";
    const std::string out = " --out " + (d / "o.mkv").string();
    const BadInput cases[] = {
        {"sim --input /no/such/clip.mp4" + out, "recording not found: /no/such/clip.mp4"},
        {"sim --input " + (d / "empty").string() + out, "no images"},
        {"sim --input " + (d / "notavideo.mp4").string() + out, "cannot decode video"},
        {"sim --events " + (d / "events.txt").string() + out, (d / "events.txt").string() + ":2:"},
        {"sim --board " + (d / "board.yaml").string(),
         (d / "board.yaml").string() + ":3: field 'video.latency_ms'"},
        {"sim --bogus", "unknown option '--bogus'"},
        {"sim --out " + (d / "o.mov").string(),
         "unsupported extension '.mov' (use .mkv, .avi or .mp4)"},
        {"sim --latency-ms x", "--latency-ms needs a number"},
        {"launch", "unknown command 'launch'"},
    };
    for (const auto& c : cases) {
        const CommandResult r = run(c.args);
        EXPECT_EQ(r.status, 2) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.message), std::string::npos) << c.args << "\n" << r.output;
    }
    // The replay watchdog's override (toolchain/cross-test.sh sets it) is checked like an
    // option; the value CI may have set is restored after.
    const char* prior = std::getenv("ENDOTOWER_REPLAY_WATCHDOG_MS");
    const std::string saved = prior != nullptr ? prior : "";
    for (const char* bad : {"2s", "0", ""}) {
        ::setenv("ENDOTOWER_REPLAY_WATCHDOG_MS", bad, 1);
        const CommandResult r = run(kBoard + out);
        EXPECT_EQ(r.status, 2) << bad << "\n" << r.output;
        EXPECT_NE(r.output.find(std::string("ENDOTOWER_REPLAY_WATCHDOG_MS='") + bad +
                                "': expected milliseconds"),
                  std::string::npos)
            << r.output;
    }
    if (prior != nullptr) ::setenv("ENDOTOWER_REPLAY_WATCHDOG_MS", saved.c_str(), 1);
    else ::unsetenv("ENDOTOWER_REPLAY_WATCHDOG_MS");
    EXPECT_FALSE(fs::exists(d / "o.mkv"));
}

}  // namespace
