// Board file parsing: values, defaults, path resolution, and errors naming the line
// and field.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "board_config.hpp"
#include "scratch_dir.hpp"

namespace endotower::firmware {
namespace {

namespace fs = std::filesystem;

std::string write_board(const std::string& name, const std::string& text) {
    // One directory per process: CTest runs the tests of this file in parallel.
    const fs::path dir = endotower::test::scratch_dir("board_test", false);
    const fs::path p = dir / name;
    std::ofstream(p) << text;
    return p.string();
}

TEST(Board, TheShippedSimBoardLoads) {
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(ENDOTOWER_SOURCE_DIR "/board/sim/board.yaml", b, err)) << err;
    EXPECT_EQ(b.name, "sim");
    EXPECT_EQ(b.stage, "status_badge");
    EXPECT_TRUE(fs::exists(b.sim_input)) << b.sim_input;
    EXPECT_TRUE(fs::exists(b.sim_events)) << b.sim_events;
    EXPECT_FALSE(b.sim_realtime);
    EXPECT_TRUE(b.gestures);
    EXPECT_TRUE(fs::exists(b.gesture_model)) << b.gesture_model;
    EXPECT_TRUE(fs::exists(b.gesture_tool_model)) << b.gesture_tool_model;
    EXPECT_NE(fs::canonical(b.gesture_tool_model), fs::canonical(b.tool_model));
    EXPECT_DOUBLE_EQ(b.gesture_hold_ms, 1000.0);
}

TEST(Board, ValuesAndRelativePaths) {
    const std::string p = write_board("ok.yaml",
                                      "board: t\n"
                                      "video: {latency_ms: 20.5, compose_budget_ms: 3}\n"
                                      "analysis: {stage: none, max_overlay_age: 5}\n"
                                      "sim: {input: clip.mp4, output: /tmp/x.mkv, realtime: yes}\n");
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(p, b, err)) << err;
    EXPECT_DOUBLE_EQ(b.latency_ms, 20.5);
    EXPECT_DOUBLE_EQ(b.compose_budget_ms, 3);
    EXPECT_EQ(b.stage, "none");
    EXPECT_EQ(b.max_overlay_age, 5);
    EXPECT_EQ(b.sim_input, (fs::path(p).parent_path() / "clip.mp4").string());
    EXPECT_EQ(b.sim_output, "/tmp/x.mkv");
    EXPECT_TRUE(b.sim_realtime);
    EXPECT_EQ(b.region_descriptor, "sift");  // the default
    const std::string q = write_board("regions.yaml",
                                      "board: t\n"
                                      "analysis:\n"
                                      "  regions: {descriptor: akaze, redetect_interval: 4, min_inliers: 12, "
                                      "detect_max_width: 640, propagate: false}\n");
    ASSERT_TRUE(load_board(q, b, err)) << err;
    EXPECT_EQ(b.region_descriptor, "akaze");
    EXPECT_EQ(b.region_redetect_interval, 4);
    EXPECT_EQ(b.region_min_inliers, 12);
    EXPECT_EQ(b.region_detect_max_width, 640);
    EXPECT_FALSE(b.region_propagate);
    EXPECT_FALSE(b.region_mark_with_tool);  // the defaults
    EXPECT_TRUE(b.fov_mask);
    const std::string r = write_board("marking.yaml",
                                      "board: t\n"
                                      "analysis:\n"
                                      "  fov_mask: false\n"
                                      "  regions: {mark_with_tool: true}\n");
    ASSERT_TRUE(load_board(r, b, err)) << err;
    EXPECT_TRUE(b.region_mark_with_tool);
    EXPECT_FALSE(b.fov_mask);
}

// analysis.regions.overlay / depth_mm / media (issue 7): values, the media folder
// resolved against the board file (sci.media when not given), errors with FILE:LINE.
TEST(Board, RegionOverlays) {
    BoardConfig b;
    std::string err;
    const std::string p = write_board("overlay.yaml",
                                      "board: t\n"
                                      "analysis:\n"
                                      "  regions: {overlay: 'image:liver.png', depth_mm: 60, media: m}\n");
    ASSERT_TRUE(load_board(p, b, err)) << err;
    EXPECT_EQ(b.region_overlay, "image:liver.png");
    EXPECT_DOUBLE_EQ(b.region_depth_mm, 60);
    EXPECT_EQ(b.region_media, (fs::path(p).parent_path() / "m").string());
    const std::string q = write_board("overlay_sci.yaml",
                                      "board: t\n"
                                      "analysis:\n"
                                      "  regions: {overlay: 'object:cube'}\n"
                                      "sci: {media: media}\n");
    ASSERT_TRUE(load_board(q, b, err)) << err;
    EXPECT_DOUBLE_EQ(b.region_depth_mm, 80);  // the default: the image box's depth
    EXPECT_EQ(b.region_media, (fs::path(q).parent_path() / "media").string());
    const std::string bad = write_board("overlay_bad.yaml",
                                        "board: t\n"
                                        "analysis:\n"
                                        "  regions:\n"
                                        "    overlay: sticker\n");
    EXPECT_FALSE(load_board(bad, b, err));
    EXPECT_NE(err.find("overlay_bad.yaml:4: field 'analysis.regions.overlay'"), std::string::npos)
        << err;
    EXPECT_NE(err.find("expected markers, image:PATH or object:cube"), std::string::npos) << err;
    const std::string no_media = write_board("overlay_no_media.yaml",
                                             "board: t\n"
                                             "analysis:\n"
                                             "  regions: {overlay: 'image:a.png'}\n");
    EXPECT_FALSE(load_board(no_media, b, err));
    EXPECT_NE(err.find("overlay_no_media.yaml:3"), std::string::npos) << err;
    EXPECT_NE(err.find("needs a media folder"), std::string::npos) << err;
    const std::string escape = write_board("overlay_escape.yaml",
                                           "board: t\n"
                                           "analysis:\n"
                                           "  regions: {media: ../../etc}\n");
    EXPECT_FALSE(load_board(escape, b, err));
    EXPECT_NE(err.find("leads out of the board file's directory"), std::string::npos) << err;
}

TEST(Board, CalibrationPathIsResolvedAgainstTheBoardFile) {
    const std::string p = write_board("cal.yaml", "board: t\ncalibration: scopes/olympus.json\n");
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(p, b, err)) << err;
    EXPECT_EQ(b.calibration, (fs::path(p).parent_path() / "scopes/olympus.json").string());
    const std::string bad = write_board("cal_bad.yaml", "board: t\ncalibration: [a, b]\n");
    EXPECT_FALSE(load_board(bad, b, err));
    EXPECT_NE(err.find("cal_bad.yaml:2: field 'calibration'"), std::string::npos) << err;
}

TEST(Board, DisplayAndPaths) {
    const std::string p = write_board("display.yaml",
                                      "board: t\n"
                                      "video: {latency_budget_ms: 18.7}\n"
                                      "display: {card: /dev/dri/card1, connector: HDMI-A-2, mode: 1280x720@50,\n"
                                      "          zero_copy: false, atomic: false}\n"
                                      "calibration: cal.json\n"
                                      "analysis: {gestures: {model: /opt/m.yml, tool_model: px.bin}}\n"
                                      "paths: {storage: store}\n");
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(p, b, err)) << err;
    EXPECT_EQ(b.display_card, "/dev/dri/card1");
    EXPECT_EQ(b.display_connector, "HDMI-A-2");
    EXPECT_EQ(b.display_width, 1280);
    EXPECT_EQ(b.display_height, 720);
    EXPECT_DOUBLE_EQ(b.display_refresh_hz, 50.0);
    EXPECT_FALSE(b.display_zero_copy);
    EXPECT_FALSE(b.display_atomic);
    EXPECT_DOUBLE_EQ(b.latency_budget_ms, 18.7);
    EXPECT_EQ(b.calibration, (fs::path(p).parent_path() / "cal.json").string());
    EXPECT_EQ(b.gesture_model, "/opt/m.yml");
    EXPECT_EQ(b.gesture_tool_model, (fs::path(p).parent_path() / "px.bin").string());
    EXPECT_EQ(b.storage, (fs::path(p).parent_path() / "store").string());

    // Defaults: 1920x1080@60 on the first card's first connected connector.
    BoardConfig d;
    ASSERT_TRUE(load_board(write_board("plain.yaml", "board: t\ndisplay: {mode: 3840x2160}\n"), d, err)) << err;
    EXPECT_EQ(d.display_card, "/dev/dri/card0");
    EXPECT_EQ(d.display_connector, "");
    EXPECT_EQ(d.display_width, 3840);
    EXPECT_DOUBLE_EQ(d.display_refresh_hz, 60.0);
    EXPECT_TRUE(d.display_zero_copy);
}

// Every shipped board loads.
TEST(Board, ShippedBoardsLoad) {
    for (const char* name : {"sim", "vhw", "rpi5", "rk3588"}) {
        BoardConfig b;
        std::string err;
        EXPECT_TRUE(load_board(std::string(ENDOTOWER_SOURCE_DIR "/board/") + name + "/board.yaml", b, err)) << err;
        EXPECT_EQ(b.name, name);
    }
}

struct BadCase {
    const char* text;
    const char* message;  // after "FILE:"
};

TEST(Board, ErrorsNameTheLineAndField) {
    const BadCase cases[] = {
        {"board: t\ndisplay:\n  mode: 1920by1080\n",
         "3: field 'display.mode': expected WIDTHxHEIGHT@HZ (e.g. 1920x1080@60), got '1920by1080'"},
        {"board: t\ndisplay:\n  mode: 1920x1080@0\n",
         "3: field 'display.mode': expected WIDTHxHEIGHT@HZ (e.g. 1920x1080@60), got '1920x1080@0'"},
        {"board: t\ndisplay:\n  conector: HDMI-A-1\n",
         "3: field 'display.conector': unknown key (expected one of: card, connector, mode, zero_copy, atomic)"},
        {"board: t\npaths:\n  storage: [a]\n", "3: field 'paths.storage': expected a string"},
        {"board: t\nvideo:\n  latency_ms: fast\n",
         "3: field 'video.latency_ms': expected a number, got 'fast'"},
        {"board: t\nvideo:\n  latency_ms: -1\n", "3: field 'video.latency_ms': must be between 0 and 1000, got -1"},
        {"board: t\nvideo:\n  latncy_ms: 3\n",
         "3: field 'video.latncy_ms': unknown key (expected one of: latency_ms, compose_budget_ms, late_tolerance_ms, latency_budget_ms)"},
        {"board: t\nanalysis:\n  stage: magic\n",
         "3: field 'analysis.stage': unknown stage 'magic' (expected status_badge or none)"},
        {"board: t\nanalysis:\n  tracker: cnn\n",
         "3: field 'analysis.tracker': unknown tracker 'cnn' (expected none, kalman, kalman_red, likelihood, ekf, mog2, "
         "particle, particle_sorted, hybrid, mhi)"},
        {"board: t\nsim:\n  realtime: maybe\n", "3: field 'sim.realtime': expected true or false, got 'maybe'"},
        {"board: t\nanalysis:\n  max_overlay_age: 2.5\n", "3: field 'analysis.max_overlay_age': expected an integer"},
        {"video: {latency_ms: 1}\n", "1: field 'board': missing (the board's name)"},
        {"board: t\nanalysis:\n  regions:\n    descriptor: surf\n",
         "4: field 'analysis.regions.descriptor': unknown descriptor 'surf' (expected sift, orb or akaze; SURF is "
         "patented and not in Debian's OpenCV)"},
        {"board: t\nanalysis:\n  regions: {min_inliers: 2}\n",
         "3: field 'analysis.regions.min_inliers': must be between 4 and 1000, got 2"},
        {"board: t\nanalysis:\n  regions:\n    redetect: 5\n",
         "4: field 'analysis.regions.redetect': unknown key (expected one of: descriptor, redetect_interval, "
         "min_inliers, detect_max_width, propagate, mark_with_tool, overlay, depth_mm, media)"},
        {"board: t\nanalysis:\n  regions: {mark_with_tool: true}\nsci: {layout: ring}\n",
         "3: field 'analysis.regions.mark_with_tool': not with sci: (the handle's button drives the interface); "
         "mark regions from the timeline or --region"},
        {"board: t\nanalysis:\n  fov_mask: sometimes\n",
         "3: field 'analysis.fov_mask': expected true or false, got 'sometimes'"},
        {"board: t\nanalysis:\n  regions: sift\n", "3: field 'analysis.regions': expected a mapping of keys"},
        {"board: t\nvideo: [1, 2\n", "3: not valid YAML: end of sequence flow not found"},
        {"board: t\n? [a, b]\n: c\n", "2: field '(top level)': a key must be a plain name"},
        {"board: t\nsim:\n  ? {x: 1}\n  : y\n", "3: field 'sim': a key must be a plain name"},
        {"board: t\nanalysis:\n  gestures: {model: g.yml, hold: 3}\n",
         "3: field 'analysis.gestures.hold': unknown key (expected one of: model, tool_model, "
         "hold_ms)"},
        {"board: t\nanalysis:\n  gestures:\n    hold_ms: 500\n",
         "4: field 'analysis.gestures.model': missing (a file of 'endotower train-gestures')"},
        {"board: t\nanalysis:\n  gestures:\n    model: g.yml\n    hold_ms: -5\n",
         "5: field 'analysis.gestures.hold_ms': must be between 0 and 60000, got -5"},
        {"board: t\nanalysis:\n  gestures: on\n",
         "3: field 'analysis.gestures': expected a map {model: FILE, tool_model: FILE, hold_ms: "
         "N}"},
    };
    for (const auto& c : cases) {
        const std::string p = write_board("bad.yaml", c.text);
        BoardConfig b;
        std::string err;
        EXPECT_FALSE(load_board(p, b, err)) << c.text;
        EXPECT_EQ(err, p + ":" + c.message) << c.text;
    }
}

// Inputs the fuzzer (tests/fuzz) once crashed on: each must now load or be refused
// with a message naming the file.
TEST(Board, FuzzRegressionsAreRefusedCleanly) {
    const fs::path dir = fs::path(ENDOTOWER_SOURCE_DIR) / "tests/fuzz/regressions/board";
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        BoardConfig b;
        std::string err;
        if (!load_board(e.path().string(), b, err)) {
            EXPECT_EQ(err.rfind(e.path().string(), 0), 0u) << err;
        }
        ++n;
    }
    EXPECT_GE(n, 1);
}

TEST(Board, TheBooksTrackersAreSelectableByName) {
    for (const char* name : {"ekf", "mog2", "particle", "particle_sorted", "hybrid", "mhi"}) {
        const std::string p = write_board("trk.yaml", std::string("board: t\nanalysis: {tracker: ") + name + "}\n");
        BoardConfig b;
        std::string err;
        EXPECT_TRUE(load_board(p, b, err)) << err;
        EXPECT_EQ(b.tracker, name);
    }
}

TEST(Board, MissingAndEmptyFiles) {
    BoardConfig b;
    std::string err;
    EXPECT_FALSE(load_board("/nonexistent/board.yaml", b, err));
    EXPECT_EQ(err, "board file not found or unreadable: /nonexistent/board.yaml");
    const std::string p = write_board("empty.yaml", "");
    EXPECT_FALSE(load_board(p, b, err));
    EXPECT_EQ(err, p + ": board file is empty");
}

}  // namespace
}  // namespace endotower::firmware

namespace endotower::firmware {
namespace {

std::string write_input_board(const std::string& text) {
    const auto dir = endotower::test::scratch_dir("board_test", false);
    const auto p = dir / "input.yaml";
    std::ofstream(p) << text;
    return p.string();
}

TEST(BoardInput, CaptureButtonHandleValuesAndDefaults) {
    const std::string p = write_input_board(
        "board: t\n"
        "capture: {device: /dev/v4l/by-id/hdmi, format: uyvy, width: 1280, height: 720, fps: 50,\n"
        "          buffers: 3, input: 3, dv_timings: 1280x720p50}\n"
        "button: {chip: endotower-button, line: 17, active_low: true, debounce_ms: 30}\n"
        "handle: {vid: 0x1209, pid: 59248, serial: A1, usage_page: 0x01}\n");
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(p, b, err)) << err;
    EXPECT_TRUE(b.capture.present);
    EXPECT_EQ(b.capture.device, "/dev/v4l/by-id/hdmi");
    EXPECT_EQ(b.capture.format, "uyvy");
    EXPECT_EQ(b.capture.width, 1280);
    EXPECT_EQ(b.capture.height, 720);
    EXPECT_DOUBLE_EQ(b.capture.fps, 50);
    EXPECT_EQ(b.capture.buffers, 3);
    EXPECT_EQ(b.capture.input, 3);
    EXPECT_EQ(b.capture.dv_timings, "1280x720p50");
    EXPECT_TRUE(b.button.present);
    EXPECT_EQ(b.button.chip, "endotower-button");
    EXPECT_EQ(b.button.line, 17);
    EXPECT_TRUE(b.button.active_low);
    EXPECT_DOUBLE_EQ(b.button.debounce_ms, 30);
    EXPECT_DOUBLE_EQ(b.button.long_press_ms, 800);  // default
    EXPECT_EQ(b.handle.vid, 0x1209);
    EXPECT_EQ(b.handle.pid, 59248);
    EXPECT_EQ(b.handle.serial, "A1");
    EXPECT_EQ(b.handle.usage_page, 1);

    const std::string q = write_input_board("board: t\ncapture: {}\n");
    BoardConfig d;
    ASSERT_TRUE(load_board(q, d, err)) << err;
    EXPECT_TRUE(d.capture.present);
    EXPECT_EQ(d.capture.device, "/dev/video0");
    EXPECT_EQ(d.capture.format, "yuyv");
    EXPECT_EQ(d.capture.buffers, 4);
    EXPECT_EQ(d.button.debounce_ms, 20);
    EXPECT_FALSE(d.button.present);
    EXPECT_FALSE(d.handle.present);
}

TEST(BoardInput, CaptureFormatMjpegIsAccepted) {
    const std::string p = write_input_board(
        "board: t\ncapture: {device: /dev/v4l/by-id/usb-cam, format: mjpeg, width: 1920, "
        "height: 1080, fps: 30}\n");
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(p, b, err)) << err;
    EXPECT_EQ(b.capture.format, "mjpeg");
}

TEST(BoardInput, ErrorsNameTheLineAndField) {
    const std::pair<const char*, const char*> cases[] = {
        {"board: t\ncapture:\n  format: rgb\n",
         "3: field 'capture.format': unknown format 'rgb' (expected yuyv, uyvy, nv12, bgrx or "
         "mjpeg)"},
        {"board: t\ncapture:\n  dv_timings: 1080p\n",
         "3: field 'capture.dv_timings': expected query or timings like 1920x1080p60, got '1080p'"},
        {"board: t\ncapture:\n  buffers: 1\n", "3: field 'capture.buffers': must be between 2 and 16, got 1"},
        {"board: t\ncapture:\n  fmt: yuyv\n",
         "3: field 'capture.fmt': unknown key (expected one of: device, format, width, height, fps, buffers, "
         "input, dv_timings)"},
        {"board: t\nbutton:\n  line: 3\n", "3: field 'button.chip': missing (gpiochip name, label or number)"},
        {"board: t\nbutton:\n  chip: c\n  debounce_ms: -5\n",
         "4: field 'button.debounce_ms': must be between 0 and 1000, got -5"},
        {"board: t\nhandle:\n  vid: 0x1209\n  pid: 0x10000\n",
         "4: field 'handle.pid': expected a 16-bit id like 0x1209, got '0x10000'"},
        {"board: t\nhandle:\n  vid: acme\n  pid: 1\n",
         "3: field 'handle.vid': expected a 16-bit id like 0x1209, got 'acme'"},
        {"board: t\nhandle:\n  vid: 0x1209\n", "3: field 'handle': vid and pid are required"},
    };
    for (const auto& [text, message] : cases) {
        const std::string p = write_input_board(text);
        BoardConfig b;
        std::string err;
        EXPECT_FALSE(load_board(p, b, err)) << text;
        EXPECT_EQ(err, p + ":" + message) << text;
    }
}

}  // namespace
}  // namespace endotower::firmware

namespace endotower::firmware {
namespace {

// Issue 10: the files a board makes the appliance read may not lie outside the board
// file's directory through a relative path, whether by ".." or by a symlink.
TEST(BoardPaths, RelativePathsMayNotLeaveTheBoardDirectory) {
    const fs::path dir = fs::temp_directory_path() / ("endotower_board_confine_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir / "boards" / "scopes");
    fs::create_directory_symlink("/etc", dir / "boards" / "etc_link");
    const std::string board = (dir / "boards" / "b.yaml").string();
    const std::string base = fs::weakly_canonical(dir / "boards").string();
    struct Case {
        const char* yaml;
        const char* field;
        const char* value;
        int line;
    };
    const Case refused[] = {
        {"board: t\ncalibration: ../../etc/passwd\n", "calibration", "../../etc/passwd", 2},
        {"board: t\ncalibration: scopes/../../x.json\n", "calibration", "scopes/../../x.json", 2},
        {"board: t\ncalibration: etc_link/passwd\n", "calibration", "etc_link/passwd", 2},
        {"board: t\nanalysis:\n  tool_model: ../m.bin\n", "analysis.tool_model", "../m.bin", 3},
        {"board: t\nanalysis:\n  gestures: {model: ../../g.yml}\n", "analysis.gestures.model", "../../g.yml", 3},
        {"board: t\nanalysis:\n  gestures: {model: g.yml, tool_model: ../p.bin}\n",
         "analysis.gestures.tool_model", "../p.bin", 3},
        {"board: t\nsim:\n  input: ../clip.mp4\n", "sim.input", "../clip.mp4", 3},
        {"board: t\nsim:\n  events: ../../../events.txt\n", "sim.events", "../../../events.txt", 3},
    };
    for (const Case& c : refused) {
        std::ofstream(board) << c.yaml;
        BoardConfig b;
        std::string err;
        EXPECT_FALSE(load_board(board, b, err)) << c.yaml;
        EXPECT_EQ(err, board + ":" + std::to_string(c.line) + ": field '" + c.field + "': '" + c.value +
                           "' leads out of the board file's directory " + base +
                           " (relative paths must stay inside it; give an absolute path instead)");
    }
    // Inside the directory (also through a ".." that stays inside), and absolute paths.
    std::ofstream(board) << "board: t\ncalibration: scopes/../scopes/a.json\nanalysis:\n  tool_model: /opt/m.bin\n"
                            "sim:\n  input: clip.mp4\n  output: ../out/x.mkv\n";
    BoardConfig b;
    std::string err;
    ASSERT_TRUE(load_board(board, b, err)) << err;
    EXPECT_EQ(b.calibration, (dir / "boards" / "scopes" / "a.json").string());
    EXPECT_EQ(b.tool_model, "/opt/m.bin");
    EXPECT_EQ(b.sim_output, (dir / "out" / "x.mkv").string());  // outputs: docs/reliability.md
    fs::remove_all(dir);
}

}  // namespace
}  // namespace endotower::firmware
