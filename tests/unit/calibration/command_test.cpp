// `endotower calibrate` end to end on simulator images written to a temporary
// folder (white background, the square chart at known distances, the two-dot marker,
// tilted chessboards seen through the same simulated scope), bad input, and the real
// endocal grid.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "calib_test_util.hpp"
#include "endotower/calibration/calibration_file.hpp"

namespace endotower::calibration::test {
namespace {

namespace fs = std::filesystem;

struct CommandRun {
    int rc = -1;
    std::string out;  // stdout + stderr
};

CommandRun run(const std::string& args) {
    const std::string cmd = std::string(ENDOTOWER_BINARY) + " calibrate " + args + " 2>&1";
    CommandRun r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    char buf[4096];
    std::size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
    const int status = pclose(p);
    r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

std::string read(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

void save(const fs::path& p, const scene::Image& img) {
    cv::imwrite(p.string(),
                cv::Mat(img.height, img.width, CV_8UC3, const_cast<std::uint8_t*>(img.bgr.data())));
}

// A 9x6-inner-corner chessboard (4 mm squares, one white square of margin) at pose
// (rvec, t mm), seen through the simulated scope: every displayed pixel undistorted,
// its ray cut with the board plane (2x2 samples), black outside the field of view.
cv::Mat render_chessboard(const scene::CameraModel& cam, const cv::Vec3d& rvec,
                          const cv::Vec3d& t) {
    cv::Matx33d rot;
    cv::Rodrigues(rvec, rot);
    const cv::Vec3d n(rot(0, 2), rot(1, 2), rot(2, 2));
    cv::Mat img(cam.height, cam.width, CV_8UC1);
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            if (!cam.in_fov(x, y)) {
                img.at<std::uint8_t>(y, x) = 0;
                continue;
            }
            double acc = 0;
            for (int s = 0; s < 4; ++s) {
                double xu, yu;
                const int col = s % 2, row = s / 2;  // the 2x2 sample grid
                const double sx = x - 0.25 + 0.5 * col, sy = y - 0.25 + 0.5 * row;
                if (!cam.undistort(sx, sy, xu, yu)) continue;
                const scene::Vec3 r = cam.ray(xu, yu);
                const cv::Vec3d ray(r.x, r.y, r.z);
                const cv::Vec3d p = ray * (n.dot(t) / n.dot(ray)) - t;
                const double u = rot(0, 0) * p[0] + rot(1, 0) * p[1] + rot(2, 0) * p[2];
                const double v = rot(0, 1) * p[0] + rot(1, 1) * p[1] + rot(2, 1) * p[2];
                // Board: squares of 4 mm from (-4, -4) to (36, 24): corners at (0..32, 0..20).
                const int i = static_cast<int>(std::floor(u / 4)) + 1,
                          j = static_cast<int>(std::floor(v / 4)) + 1;
                double level = 0.85;
                if (i >= 0 && i < 10 && j >= 0 && j < 7)
                    level = (i + j) % 2 ? 0.9 : 0.1;
                else if (i < -1 || i > 10 || j < -1 || j > 7)
                    level = 0.5;
                acc += level;
            }
            img.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(acc / 4 * 255);
        }
    cv::GaussianBlur(img, img, cv::Size(0, 0), 0.5);
    return img;
}

class CalibrateCommand : public ::testing::Test {
protected:
    static inline fs::path dir;
    static inline scene::CameraModel cam;

    static void SetUpTestSuite() {
        dir = fs::temp_directory_path() / ("endotower_calibrate_" + std::to_string(getpid()));
        fs::remove_all(dir);
        fs::create_directories(dir);
        std::string error;
        scene::SceneRenderer white;
        ASSERT_TRUE(white.init(scenario_or_fail(kWhite), 26, error)) << error;
        cam = white.camera();
    }
    static void TearDownTestSuite() { fs::remove_all(dir); }

    static inline const char* kWhite =
        "frames: 2\nlight: 0.7\ntarget: {kind: white, distances_mm: 40}\n";

    // Renders `scenario` into `sub`, naming frame i with `name(truth)`.
    static void render_folder(const std::string& sub, const char* scenario, int seed,
                              std::string (*name)(const scene::FrameTruth&, int)) {
        fs::create_directories(dir / sub);
        scene::SceneRenderer r;
        std::string error;
        ASSERT_TRUE(r.init(scenario_or_fail(scenario), seed, error)) << error;
        scene::Image img;
        scene::FrameTruth truth;
        for (int i = 0; i < r.frames(); ++i) {
            r.render(i, img, truth);
            save(dir / sub / name(truth, i), img);
        }
    }
    static std::string by_distance(const scene::FrameTruth& t, int) {
        char b[32];
        std::snprintf(b, sizeof b, "%03.0fmm.png", t.target.distance_mm);
        return b;
    }
    static std::string by_index(const scene::FrameTruth&, int i) {
        return "white" + std::to_string(i) + ".png";
    }

    // The folder `sub` ("white", "chart", "marker", "chess"), rendered on first use
    // (each test runs in its own process under ctest: render only what it needs).
    static std::string d(const char* sub) {
        static std::set<std::string> made;
        if (made.insert(sub).second) {
            const std::string s = sub;
            if (s == "white") render_folder(s, kWhite, 26, by_index);
            if (s == "chart")
                render_folder(
                    s,
                    "frames: 6\nlight: 0.9\ntarget: {kind: squares, pitch_mm: 8, size_mm: 4, "
                    "cols: 15, rows: 13, distances_mm: [50, 40, 60, 70, 80, 90]}\n",
                    23, by_distance);
            if (s == "marker")
                render_folder(
                    s,
                    "frames: 6\nlight: 1.0\ntarget: {kind: two_dot, dot_mm: 3, separation_mm: "
                    "10, distances_mm: [30, 50, 70, 80, 120, 200]}\n",
                    33, by_distance);
            if (s == "chess") {
                fs::create_directories(dir / s);
                const double poses[8][6] = {
                    {0.45, 0, 0, -16, -10, 62},       {-0.45, 0.1, 0.1, -16, -10, 64},
                    {0, 0.45, -0.1, -16, -10, 60},    {0.1, -0.45, 0.2, -16, -10, 66},
                    {0.35, 0.35, 0.3, -16, -10, 68},  {-0.35, -0.35, -0.2, -16, -10, 63},
                    {0.35, -0.35, 0.5, -16, -10, 66}, {-0.35, 0.35, -0.5, -16, -10, 66}};
                for (int i = 0; i < 8; ++i)
                    cv::imwrite((dir / s / ("view" + std::to_string(i) + ".png")).string(),
                                render_chessboard(cam, {poses[i][0], poses[i][1], poses[i][2]},
                                                  {poses[i][3], poses[i][4], poses[i][5]}));
            }
        }
        return (dir / sub).string();
    }
};

// Both methods on the same simulated scope; the file holds OpenCV's model plus the
// book's circle, polynomial and separation table; the comparison is printed.
TEST_F(CalibrateCommand, BothMethodsOnTheSimulatedScope) {
    const fs::path out = dir / "scope1.json";
    const CommandRun r =
        run("--images " + d("chess") + " --target chessboard:9x6 --spacing 4 --white " +
            d("white") + " --chart " + d("chart") + " --marker " + d("marker") + " --out " +
            out.string() + " --scope sim-scope-1");
    std::printf("%s", r.out.c_str());
    ASSERT_EQ(r.rc, 0) << r.out;
    Calibration c;
    std::string error;
    ASSERT_TRUE(load_calibration(out.string(), c, error)) << error;
    EXPECT_EQ(c.scope, "sim-scope-1");
    EXPECT_EQ(c.model, LensModel::kPinhole);
    EXPECT_LE(c.rms, 0.5);
    EXPECT_NEAR(c.fx, cam.fx, 0.01 * cam.fx);
    EXPECT_NEAR(c.fy, cam.fy, 0.01 * cam.fy);
    EXPECT_NEAR(c.cx, cam.cx, 2.0);
    EXPECT_NEAR(c.cy, cam.cy, 2.0);
    EXPECT_NEAR(c.fov.cx, cam.fov_cx, 1.0);
    EXPECT_NEAR(c.fov.cy, cam.fov_cy, 1.0);
    ASSERT_TRUE(c.book.has_value());
    EXPECT_NEAR(c.book->cx, cam.cx, 1.0);
    EXPECT_NEAR(c.book->cy, cam.cy, 1.0);
    ASSERT_TRUE(c.separation.has_value());
    EXPECT_EQ(c.separation->distances_mm, (std::vector<double>{30, 50, 70, 80, 120, 200}));
    for (const char* s : {"table 2.3", "comparison (book vs OpenCV pinhole)",
                          "reprojection RMS on the 8 target views",
                          "mean distance error on 6 chart images", "separation: 70.0 mm"})
        EXPECT_NE(r.out.find(s), std::string::npos) << s;
}

// --undistorted: the chessboard views through the calibration's own remap. The
// corners of every row of the board lie on a straight line in the undistorted images
// (the simulated lens bends them by pixels), the images keep their names and size.
TEST_F(CalibrateCommand, UndistortedViewsHaveStraightRows) {
    const fs::path out = dir / "scope-u.json", und = dir / "undistorted";
    const CommandRun r = run("--images " + d("chess") + " --target chessboard:9x6 --spacing 4 " +
                             "--out " + out.string() + " --undistorted " + und.string());
    ASSERT_EQ(r.rc, 0) << r.out;
    EXPECT_NE(r.out.find("undistorted image(s) to"), std::string::npos) << r.out;
    // Mean distance of the inner corners from the line through their row's end corners.
    auto bend = [](const std::vector<cv::Point2f>& c) {
        double sum = 0;
        for (int row = 0; row < 6; ++row) {
            const cv::Point2f a = c[row * 9], b = c[row * 9 + 8];
            const cv::Point2f n(-(b.y - a.y), b.x - a.x);
            const double len = std::hypot(n.x, n.y);
            for (int i = 1; i < 8; ++i) {
                const cv::Point2f p = c[row * 9 + i] - a;
                sum += std::abs(p.x * n.x + p.y * n.y) / len;
            }
        }
        return sum / 42;
    };
    int compared = 0;
    double worst_in = 0, worst_out = 0;  // sums over the views
    for (const auto& e : fs::directory_iterator(d("chess"))) {
        const cv::Mat in = cv::imread(e.path().string(), cv::IMREAD_GRAYSCALE);
        const fs::path up = und / (e.path().stem().string() + ".png");
        ASSERT_TRUE(fs::exists(up)) << up;
        const cv::Mat u = cv::imread(up.string(), cv::IMREAD_GRAYSCALE);
        ASSERT_EQ(u.size(), in.size());
        std::vector<cv::Point2f> ci, cu;
        if (!cv::findChessboardCorners(in, {9, 6}, ci) || !cv::findChessboardCorners(u, {9, 6}, cu))
            continue;
        const cv::TermCriteria term(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 40, 0.01);
        cv::cornerSubPix(in, ci, {5, 5}, {-1, -1}, term);
        cv::cornerSubPix(u, cu, {5, 5}, {-1, -1}, term);
        worst_in += bend(ci);
        worst_out += bend(cu);
        ++compared;
    }
    ASSERT_GE(compared, 4);
    const double mean_in = worst_in / compared, mean_out = worst_out / compared;
    std::printf("row bend: %d views, distorted %.3f px, undistorted %.3f px\n", compared, mean_in,
                mean_out);
    Calibration c;
    std::string error;
    ASSERT_TRUE(load_calibration(out.string(), c, error)) << error;
    // Undistorted, the rows are straight to within the calibration's own reprojection
    // error, and several times straighter than the lens shows them.
    EXPECT_LT(mean_out, c.rms);
    EXPECT_LT(3 * mean_out, mean_in);
}

// --live: the board's camera is a recording of the technician at work: each of the 8
// chessboard poses held for 3 frames, a frame without the target between poses. Each
// pose is kept once (a held pose is the same view), the calibration equals the
// folder's within the sim's bounds, and the kept views are saved.
TEST_F(CalibrateCommand, LiveViewsFromTheBoardsCamera) {
    const fs::path live = dir / "live";
    fs::remove_all(live);
    fs::create_directories(live / "frames");
    int frame = 0;
    std::vector<fs::path> views;
    for (const auto& e : fs::directory_iterator(d("chess"))) views.push_back(e.path());
    std::sort(views.begin(), views.end());
    const cv::Mat blank(cam.height, cam.width, CV_8UC1, cv::Scalar(0));
    auto put = [&](const cv::Mat& m) {
        char name[32];
        std::snprintf(name, sizeof name, "%03d.png", frame++);
        cv::imwrite((live / "frames" / name).string(), m);
    };
    for (const fs::path& v : views) {
        const cv::Mat m = cv::imread(v.string(), cv::IMREAD_GRAYSCALE);
        for (int i = 0; i < 3; ++i) put(m);
        put(blank);
    }
    // 4 fps: every frame is looked at (250 ms apart).
    std::ofstream(live / "board.yaml") << "board: live-test\nsim:\n  input: frames\n  fps: 4\n";
    const fs::path out = live / "scope.json";
    const CommandRun r = run("--live " + (live / "board.yaml").string() +
                             " --target chessboard:9x6 --spacing 4 --views 20 --out " +
                             out.string() + " --save-views " + (live / "kept").string());
    ASSERT_EQ(r.rc, 0) << r.out;
    for (int i = 1; i <= 8; ++i)
        EXPECT_NE(r.out.find("view " + std::to_string(i) + "/20 kept: frame " +
                             std::to_string(4 * (i - 1))),
                  std::string::npos)
            << i << "\n"
            << r.out;
    EXPECT_EQ(r.out.find("view 9/20"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("end of " + (live / "frames").string() + " after 32 frames"),
              std::string::npos)
        << r.out;
    Calibration c;
    std::string error;
    ASSERT_TRUE(load_calibration(out.string(), c, error)) << error;
    EXPECT_LE(c.rms, 0.5);
    EXPECT_NEAR(c.fx, cam.fx, 0.01 * cam.fx);
    EXPECT_NEAR(c.fy, cam.fy, 0.01 * cam.fy);
    EXPECT_NEAR(c.cx, cam.cx, 2.0);
    EXPECT_NEAR(c.cy, cam.cy, 2.0);
    int saved = 0;
    for (const auto& e : fs::directory_iterator(live / "kept"))
        saved += e.path().extension() == ".png";
    EXPECT_EQ(saved, 8);

    // Bad input: a board without a camera, too few views, the squares chart; the
    // previous file is untouched.
    std::ofstream(live / "nocam.yaml") << "board: nocam\n";
    const std::string before = read(out);
    const CommandRun nocam = run("--live " + (live / "nocam.yaml").string() +
                                 " --target chessboard:9x6 --out " + out.string());
    EXPECT_EQ(nocam.rc, 2);
    EXPECT_NE(nocam.out.find("the board has no camera"), std::string::npos) << nocam.out;
    std::ofstream(live / "few.yaml") << "board: few\nsim:\n  input: frames\n  fps: 4\n";
    fs::remove_all(live / "frames");
    fs::create_directories(live / "frames");
    frame = 0;
    for (int i = 0; i < 6; ++i) put(blank);
    const CommandRun few = run("--live " + (live / "few.yaml").string() +
                               " --target chessboard:9x6 --out " + out.string());
    EXPECT_EQ(few.rc, 2);
    EXPECT_NE(few.out.find("only 0 distinct views of the target in 6 frames"), std::string::npos)
        << few.out;
    const CommandRun sq =
        run("--live " + (live / "few.yaml").string() + " --target squares --model book --white " +
            d("white") + " --out " + out.string());
    EXPECT_EQ(sq.rc, 2);
    EXPECT_NE(sq.out.find("--live takes OpenCV's targets"), std::string::npos) << sq.out;
    EXPECT_EQ(read(out), before);
}

// The book's model alone from the square chart: centre and focal length of the sim.
TEST_F(CalibrateCommand, BookModelFromTheSquareChart) {
    const fs::path out = dir / "book.json";
    const CommandRun r =
        run("--images " + d("chart") + " --target squares --spacing 8 --model book --white " +
            d("white") + " --out " + out.string());
    ASSERT_EQ(r.rc, 0) << r.out;
    Calibration c;
    std::string error;
    ASSERT_TRUE(load_calibration(out.string(), c, error)) << error;
    EXPECT_EQ(c.model, LensModel::kBook);
    EXPECT_EQ(c.scope, "book");
    EXPECT_EQ(c.distortion.size(), 2u);  // order 3
    EXPECT_NEAR(c.cx, cam.cx, 1.0);
    EXPECT_NEAR(c.cy, cam.cy, 1.0);
    EXPECT_NEAR(c.fx, cam.fx, 0.02 * cam.fx);
    EXPECT_NEAR(c.fy, cam.fy, 0.02 * cam.fy);
    EXPECT_EQ(c.width, 640);
}

// Bad input: exit 2, the message names the image and what is missing, and the
// previous calibration file is untouched.
TEST_F(CalibrateCommand, BadInputLeavesThePreviousFile) {
    const fs::path out = dir / "previous.json";
    const std::string previous = "{\"previous\": true}\n";
    std::ofstream(out) << previous;
    const fs::path bad = dir / "bad";
    auto fresh = [&](const char* sub) {
        fs::remove_all(bad / sub);
        fs::create_directories(bad / sub);
        return (bad / sub).string();
    };
    // No circle: a grey white-background image.
    const std::string nocircle = fresh("nocircle");
    cv::imwrite(nocircle + "/grey.png", cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)));
    // Grid not found: a chart image without squares.
    const std::string nogrid = fresh("nogrid");
    fs::copy_file(d("white") + "/white0.png", nogrid + "/050mm.png");
    // Too few views: two chessboards.
    const std::string few = fresh("few");
    cv::imwrite(few + "/a.png", render_chessboard(cam, {0.45, 0, 0}, {-16, -10, 62}));
    cv::imwrite(few + "/b.png", render_chessboard(cam, {0, 0.45, -0.1}, {-16, -10, 60}));
    // Mixed sizes.
    const std::string mixed = fresh("mixed");
    for (int i = 0; i < 2; ++i)
        fs::copy_file(d("white") + "/white" + std::to_string(i) + ".png",
                      mixed + "/" + std::to_string(i) + ".png");
    cv::imwrite(mixed + "/9small.png", cv::Mat(240, 320, CV_8UC1, cv::Scalar(128)));
    const std::string o = " --out " + out.string();
    const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
        {"--images " + d("chart") + " --target squares --model book --white " + nocircle + o,
         {"grey.png", "no illuminated circle"}},
        {"--images " + nogrid + " --target squares --model book --white " + d("white") + o,
         {"050mm.png", "grid not found"}},
        {"--images " + few + " --target chessboard:9x6" + o, {"too few views", "2 image(s)"}},
        {"--images " + mixed + " --target chessboard:9x6" + o, {"9small.png", "mixed sizes"}},
        {"--images " + d("white") + " --target chessboard:9x6 --order 4 --model book --white " +
             d("white") + o,
         {"--order"}},
        {"--images " + d("white") + " --target chessboard:9x6", {"give --out"}},
        {"--images " + dir.string() + "/none --target chessboard:9x6" + o,
         {"/none", "cannot read the folder"}},
        {"--images " + d("white") + " --target chessboard:9x6 --bogus 1" + o,
         {"unknown option '--bogus'"}},
        {"--images " + d("chart") + " --target squares --model pinhole" + o, {"--model book"}},
    };
    for (const auto& [args, what] : cases) {
        const CommandRun r = run(args);
        EXPECT_EQ(r.rc, 2) << args << "\n" << r.out;
        for (const std::string& w : what)
            EXPECT_NE(r.out.find(w), std::string::npos) << w << " in:\n" << r.out;
        EXPECT_EQ(read(out), previous) << args;
    }
}

// The real endocal grid through the command: OpenCV's asymmetric layout (2,1) gives
// RMS <= 0.5 px with all 11 frames (the "3,1" layout's refusal: zhang_test.cpp).
TEST_F(CalibrateCommand, EndocalGrid) {
    const std::string data = shared_data("endocal/sample_001");
    if (!fs::is_directory(data))
        GTEST_SKIP() << "no real data at " << data << " (../shared/data absent)";
    const fs::path out = dir / "endocal.json";
    CommandRun r = run("--images " + data +
                       " --target asymmetric-circles:3x11 --spacing 2,1 --out " + out.string());
    ASSERT_EQ(r.rc, 0) << r.out;
    Calibration c;
    std::string error;
    ASSERT_TRUE(load_calibration(out.string(), c, error)) << error;
    EXPECT_LE(c.rms, 0.5);
    EXPECT_NE(r.out.find("11 of 11 images used"), std::string::npos) << r.out;
}

// The firmware loads the board's calibration file, validates it and names it in
// every trace line (file, scope, hash) with the per-frame field-of-view check: the
// scope's own frames read "ok"; against a calibration whose circle sits 8 px
// elsewhere they read "shifted". A broken calibration file stops the run (exit 2).
TEST_F(CalibrateCommand, SimRecordsTheCalibrationInTheTrace) {
    const fs::path frames = dir / "simin";
    fs::create_directories(frames);
    for (int i = 0; i < 6; ++i)
        fs::copy_file(d("white") + "/white" + std::to_string(i % 2) + ".png",
                      frames / ("00000" + std::to_string(i) + ".png"),
                      fs::copy_options::overwrite_existing);
    Calibration c;
    c.scope = "sim-scope-2";
    c.width = cam.width, c.height = cam.height;
    c.fx = cam.fx, c.fy = cam.fy, c.cx = cam.cx, c.cy = cam.cy;
    c.distortion = {0, 0, 0, 0, 0};
    c.fov = {cam.fov_cx, cam.fov_cy, cam.fov_radius};
    for (const double offset : {0.0, 8.0}) {
        c.fov.cx = cam.fov_cx + offset;
        const std::string text = format_calibration(c);
        const fs::path cal = dir / "board_cal.json";
        std::ofstream(cal) << text;
        const fs::path board = dir / "board.yaml";
        std::ofstream(board) << "board: t\ncalibration: board_cal.json\nanalysis: {stage: none}\n";
        const fs::path trace = dir / "trace.jsonl";
        const std::string cmd = std::string(ENDOTOWER_BINARY) + " sim --board " + board.string() +
                                " --input " + frames.string() + " --frames " +
                                (dir / "simout").string() + " --trace " + trace.string() +
                                " > /dev/null 2>&1";
        ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
        std::ifstream in(trace);
        std::string line;
        int lines = 0, with = 0;
        const std::string expect = "\"calibration\":{\"file\":\"" + cal.string() +
                                   "\",\"scope\":\"sim-scope-2\",\"hash\":\"" + content_hash(text) +
                                   "\",\"fov\":\"" + (offset == 0 ? "ok" : "shifted") + "\"";
        while (std::getline(in, line)) {
            ++lines;
            with += line.find(expect) != std::string::npos;
        }
        EXPECT_GE(lines, 5);
        // Every frame that shows an analysis result carries the member.
        EXPECT_GE(with, lines - 2) << expect << "\nlast line: " << line;
    }
    std::ofstream(dir / "board_cal.json") << "{\"fx\": 1}";
    const std::string cmd = std::string(ENDOTOWER_BINARY) + " sim --board " +
                            (dir / "board.yaml").string() + " --input " + frames.string() +
                            " --frames " + (dir / "simout").string() + " > /dev/null 2>&1";
    const int status = std::system(cmd.c_str());
    EXPECT_EQ(WEXITSTATUS(status), 2);
}

}  // namespace
}  // namespace endotower::calibration::test
