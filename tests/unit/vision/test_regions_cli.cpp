// Region tracking end to end: `endotower scene` renders table 6.5's emulated changes
// with truth, `endotower sim --region` tracks the truth's first-frame polygon, and
// `endotower eval` scores it (GOOD in every frame); image pairs of different sizes,
// timeline region marks, and bad region input.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "endotower_command.hpp"
#include "region_test_util.hpp"

namespace endotower::vision {
namespace {

namespace fs = std::filesystem;

using endotower::test::CommandRun;
CommandRun run(const std::string& args) {
    return endotower::test::run_endotower(args);
}

fs::path temp_dir(const std::string& name) {
    fs::path d = fs::temp_directory_path() /
                 ("endotower_regions_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

// A board with no other analysis, so only the region stage runs.
fs::path board(const fs::path& dir) {
    fs::path b = dir / "board.yaml";
    std::ofstream(b) << "board: regions_test\nanalysis:\n  stage: none\n  tracker: none\n";
    return b;
}

std::string quote(const std::string& s) {
    return "'" + s + "'";
}

std::vector<nlohmann::json> read_lines(const fs::path& p) {
    std::vector<nlohmann::json> out;
    std::ifstream in(p);
    for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
    return out;
}

class T65Suite : public ::testing::TestWithParam<int> {};

// Table 6.5's six emulated changes, 640x480: GOOD in every frame, mean corner error
// <= 3 px, with the default method (SIFT keyframes, LK propagation).
TEST_P(T65Suite, GoodInEveryFrame) {
    const std::string n = std::to_string(GetParam());
    const fs::path dir = temp_dir("t65_" + n);
    const CommandRun scene =
        run("scene --scenario " ENDOTOWER_SOURCE_DIR "/board/sim/scenarios/t65_emulated_" + n +
            ".yaml --out " + (dir / "scene").string());
    ASSERT_EQ(scene.status, 0) << scene.output;
    const nlohmann::json first = read_lines(dir / "scene/truth.jsonl").at(0);
    std::string region;
    for (const auto& v : first["regions"][0]["polygon_px"])
        region += (region.empty() ? "" : " ") + std::to_string(v[0].get<double>()) + "," +
                  std::to_string(v[1].get<double>());
    const CommandRun sim =
        run("sim --board " + board(dir).string() + " --input " + (dir / "scene/frames").string() +
            " --out " + (dir / "o.avi").string() + " --trace " + (dir / "trace.jsonl").string() +
            " --region " + quote(region));
    ASSERT_EQ(sim.status, 0) << sim.output;
    const CommandRun eval =
        run("eval --trace " + (dir / "trace.jsonl").string() + " --truth " +
            (dir / "scene/truth.jsonl").string() + " --min-region-good 100% --max-corner-error 3");
    EXPECT_EQ(eval.status, 0) << eval.output;
    EXPECT_NE(eval.output.find("regions: 24 region-frames: GOOD 24, OK 0, FAIL 0"),
              std::string::npos)
        << eval.output;
    fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Emulated, T65Suite, ::testing::Range(1, 7));

// A board whose regions anchor an image from media/ (a 64x48 PNG written here).
fs::path image_board(const fs::path& dir) {
    fs::create_directories(dir / "media");
    cv::Mat img(48, 64, CV_8UC3, cv::Scalar(40, 200, 240));
    img(cv::Rect(0, 0, 32, 24)).setTo(cv::Scalar(255, 0, 0));
    cv::imwrite((dir / "media/logo.png").string(), img);
    fs::path b = dir / "board_image.yaml";
    std::ofstream(b) << "board: regions_test\nanalysis:\n  stage: none\n  tracker: none\n"
                        "  regions: {media: media}\n";
    return b;
}

class T65AnchoredImage : public ::testing::TestWithParam<int> {};

// An image anchored to the region on table 6.5's emulated changes: shown on every frame
// (the region is tracked on all), and its corners, against the truth's homography
// (H_from_first) applied to the image fitted into the marked box, within the region
// tracker's bounds: GOOD's 0.10 x sqrt(region area) on every frame, <= 3 px mean.
TEST_P(T65AnchoredImage, CornersFollowTheTruth) {
    const std::string n = std::to_string(GetParam());
    const fs::path dir = temp_dir("anchored_" + n);
    const CommandRun scene =
        run("scene --scenario " ENDOTOWER_SOURCE_DIR "/board/sim/scenarios/t65_emulated_" + n +
            ".yaml --out " + (dir / "scene").string());
    ASSERT_EQ(scene.status, 0) << scene.output;
    const auto truth = read_lines(dir / "scene/truth.jsonl");
    std::string region;
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (const auto& v : truth.at(0)["regions"][0]["polygon_px"]) {
        const double x = v[0].get<double>(), y = v[1].get<double>();
        region += (region.empty() ? "" : " ") + std::to_string(x) + "," + std::to_string(y);
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
    const CommandRun sim = run(
        "sim --board " + image_board(dir).string() + " --input " + (dir / "scene/frames").string() +
        " --out " + (dir / "o.avi").string() + " --trace " + (dir / "trace.jsonl").string() +
        " --region " + quote(region + " overlay=image:logo.png"));
    ASSERT_EQ(sim.status, 0) << sim.output;
    // The 64x48 image fitted (aspect kept, centred) into the marked box.
    const double scale = std::min((x1 - x0) / 64, (y1 - y0) / 48);
    const double l = x0 + (x1 - x0 - 64 * scale) / 2, t = y0 + (y1 - y0 - 48 * scale) / 2;
    const double fx[4] = {l, l + 64 * scale, l + 64 * scale, l};
    const double fy[4] = {t, t, t + 48 * scale, t + 48 * scale};
    const auto trace = read_lines(dir / "trace.jsonl");
    ASSERT_EQ(trace.size(), truth.size());
    double sum = 0;
    for (std::size_t f = 0; f < trace.size(); ++f) {
        const auto& a = trace[f].at("anchored").at(0);
        ASSERT_EQ(a.at("kind"), "image");
        ASSERT_TRUE(a.at("shown").get<bool>()) << "frame " << f;
        const auto& tr = truth[f]["regions"][0];
        const auto h = tr["H_from_first"].get<std::vector<double>>();
        double area = 0;
        const auto& poly = tr["polygon_px"];
        for (std::size_t i = 0; i < poly.size(); ++i) {
            const auto &p = poly[i], &q = poly[(i + 1) % poly.size()];
            area +=
                p[0].get<double>() * q[1].get<double>() - q[0].get<double>() * p[1].get<double>();
        }
        double err = 0;
        for (int k = 0; k < 4; ++k) {
            const double w = h[6] * fx[k] + h[7] * fy[k] + h[8];
            const double u = (h[0] * fx[k] + h[1] * fy[k] + h[2]) / w;
            const double v = (h[3] * fx[k] + h[4] * fy[k] + h[5]) / w;
            err += std::hypot(a["corners_px"][k][0].get<double>() - u,
                              a["corners_px"][k][1].get<double>() - v) /
                   4;
        }
        EXPECT_LE(err, 0.10 * std::sqrt(std::abs(area) / 2)) << "frame " << f;
        sum += err;
    }
    const double mean = sum / static_cast<double>(trace.size());
    EXPECT_LE(mean, 3.0);
    std::printf("t65_emulated_%s: anchored image mean corner error %.2f px\n", n.c_str(), mean);
    fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Emulated, T65AnchoredImage, ::testing::Range(1, 7));

// Overlay input: a bad kind or a path out of the media folder is bad usage (exit 2, the
// option named); a missing image is said on stderr and the video goes on (exit 0).
TEST(RegionsCommand, AnchoredOverlayInput) {
    const fs::path dir = temp_dir("overlay_input");
    const cv::Mat a = test::texture(640, 480, 21);
    fs::create_directories(dir / "in");
    cv::imwrite((dir / "in/000000.png").string(), a);
    cv::imwrite((dir / "in/000001.png").string(), a);
    const std::string sim = "sim --board " + image_board(dir).string() + " --input " +
                            (dir / "in").string() + " --frames " + (dir / "out").string() +
                            " --trace " + (dir / "t.jsonl").string() + " --region ";
    const std::string poly = "220,160 420,170 410,330 230,320";
    CommandRun r = run(sim + quote(poly + " overlay=sticker"));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("expected markers, image:PATH or object:cube"), std::string::npos)
        << r.output;
    r = run(sim + quote(poly + " overlay=image:../secret.png"));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("inside the media folder"), std::string::npos) << r.output;
    r = run(sim + quote(poly + " overlay=image:missing.png"));
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("region 0: image not loaded"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("missing.png"), std::string::npos) << r.output;
    const auto lines = read_lines(dir / "t.jsonl");
    ASSERT_EQ(lines.size(), 2u);
    EXPECT_FALSE(lines[1].at("anchored").at(0).at("shown").get<bool>());
    // An object without a calibration: the message instead, the video goes on.
    r = run(sim + quote(poly + " overlay=object:cube"));
    EXPECT_EQ(r.status, 0) << r.output;
    // A timeline mark's overlay is checked with its file and line.
    std::ofstream(dir / "events.txt")
        << "# marks\nframe 1 region " << poly << " overlay=object:teapot\n";
    r = run(sim + quote(poly) + " --events " + (dir / "events.txt").string());
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("events.txt:2: overlay 'object:teapot': unknown object 'teapot'"),
              std::string::npos)
        << r.output;
    fs::remove_all(dir);
}

// A directory of two images of different sizes: the second is the first scaled by
// 1.25 and shifted. The trace reports the region in the second image's own pixels;
// eval scores it against the known homography.
TEST(RegionsCommand, ImagePairOfDifferentSizes) {
    const fs::path dir = temp_dir("pair");
    fs::create_directories(dir / "pair");
    const cv::Mat a = test::texture(640, 480, 21);
    cv::Mat b;
    const cv::Matx33d h(1.25, 0, 12, 0, 1.25, -8, 0, 0, 1);
    cv::warpPerspective(a, b, cv::Mat(h), cv::Size(800, 600), cv::INTER_LINEAR, cv::BORDER_REFLECT);
    cv::imwrite((dir / "pair/000000.png").string(), a);
    cv::imwrite((dir / "pair/000001.png").string(), b);
    std::ofstream(dir / "h.txt") << "1.25 0 12\n0 1.25 -8\n0 0 1\n";
    const std::string region = "220,160 420,170 410,330 230,320";
    const CommandRun sim =
        run("sim --board " + board(dir).string() + " --input " + (dir / "pair").string() +
            " --frames " + (dir / "out").string() + " --trace " + (dir / "trace.jsonl").string() +
            " --region " + quote(region));
    ASSERT_EQ(sim.status, 0) << sim.output;
    const auto lines = read_lines(dir / "trace.jsonl");
    ASSERT_EQ(lines.size(), 2u);
    EXPECT_EQ(lines[1].at("regions").at(0).at("state"), "tracked");
    const CommandRun eval =
        run("eval --trace " + (dir / "trace.jsonl").string() + " --homography " +
            (dir / "h.txt").string() + " --region " + quote(region) + " --max-corner-error 1");
    EXPECT_EQ(eval.status, 0) << eval.output;
    fs::remove_all(dir);
}

// A region marked from the timeline at frame 2 (time 0.1 s at 25 fps = frame 3 for
// the second): no regions member before it, tracked from then on, ids after --region's.
TEST(RegionsCommand, TimelineMarksARegionAtItsFrame) {
    const fs::path dir = temp_dir("timeline");
    fs::create_directories(dir / "frames");
    const cv::Mat img = test::texture(640, 480, 5);
    for (int i = 0; i < 5; ++i)
        cv::imwrite((dir / "frames" / ("00000" + std::to_string(i) + ".png")).string(), img);
    std::ofstream(dir / "events.txt") << "frame 2 region 100,100 300,100 300,300 100,300\n"
                                         "t 0.1 region 350,120 560,140 520,400\n";
    const CommandRun sim =
        run("sim --board " + board(dir).string() + " --input " + (dir / "frames").string() +
            " --out " + (dir / "o.avi").string() + " --trace " + (dir / "trace.jsonl").string() +
            " --events " + (dir / "events.txt").string());
    ASSERT_EQ(sim.status, 0) << sim.output;
    const auto lines = read_lines(dir / "trace.jsonl");
    ASSERT_EQ(lines.size(), 5u);
    EXPECT_FALSE(lines[1].contains("regions"));
    ASSERT_EQ(lines[2].at("regions").size(), 1u);
    EXPECT_EQ(lines[2].at("regions").at(0).at("id"), 0);
    EXPECT_EQ(lines[2].at("regions").at(0).at("polygon_px").at(2).at(0), 300.0);
    ASSERT_EQ(lines[4].at("regions").size(), 2u);
    EXPECT_EQ(lines[4].at("regions").at(1).at("id"), 1);
    EXPECT_EQ(lines[4].at("regions").at(1).at("state"), "tracked");
    EXPECT_NEAR(lines[4].at("regions").at(1).at("polygon_px").at(1).at(0).get<double>(), 560.0,
                0.5);
    fs::remove_all(dir);
}

TEST(RegionsCommand, BadRegionsExitTwoWithTheReason) {
    const fs::path dir = temp_dir("bad");
    fs::create_directories(dir / "frames");
    cv::imwrite((dir / "frames/000000.png").string(),
                cv::Mat(120, 160, CV_8UC3, cv::Scalar(80, 60, 150)));
    const std::string base = "sim --board " + board(dir).string() + " --input " +
                             (dir / "frames").string() + " --out " + (dir / "o.avi").string() +
                             " --region ";
    CommandRun r = run(base + quote("10,10 50,10 50"));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("endotower sim: --region \"10,10 50,10 50\": polygon vertex '50' must "
                            "be x,y (two numbers)"),
              std::string::npos)
        << r.output;
    r = run(base + quote("10,10 50,10"));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("a polygon needs at least 3 vertices"), std::string::npos) << r.output;
    // Well formed, but a flat colour has no features to follow.
    r = run(base + quote("10,10 100,10 100,100 10,100"));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("endotower sim: cannot mark a region: frame 0: region 0: only 0 sift "
                            "features inside the "
                            "polygon (need 10)"),
              std::string::npos)
        << r.output;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace endotower::vision
