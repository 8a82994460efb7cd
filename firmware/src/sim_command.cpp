#include "commands.hpp"

#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>

#include "analysis_chain.hpp"
#include "board_config.hpp"
#include "endotower/gles/gles_renderer.hpp"
#include "endotower/app/pipeline.hpp"
#include "endotower/app/stage_chain.hpp"
#include "endotower/app/status_badge.hpp"
#include "endotower/app/trace_writer.hpp"
#include "endotower/calibration/calibration_stage.hpp"
#include "endotower/calibration/undistorter.hpp"
#include "endotower/hal/control_merge.hpp"
#include "endotower/sim/file_sink.hpp"
#include "endotower/sim/recorded_source.hpp"
#include "endotower/sim/scripted_input.hpp"
#include "endotower/sim/virtual_clock.hpp"
#include "endotower/system/monotonic_clock.hpp"
#include "endotower/system/syscall.hpp"
#include "endotower/vision/kalman_tool_tracker.hpp"
#include "endotower/eval/derived_truth.hpp"
#include "endotower/vision/gesture_stage.hpp"
#include "endotower/vision/likelihood_tool_tracker.hpp"
#include "endotower/vision/region_stage.hpp"
#include "endotower/vision/tool_tracking_stage.hpp"

#ifndef ENDOTOWER_DEFAULT_BOARD
#define ENDOTOWER_DEFAULT_BOARD "board/sim/board.yaml"
#endif

namespace endotower::firmware {

namespace {

namespace fs = std::filesystem;

app::Pipeline* g_running = nullptr;
extern "C" void on_signal(int) {
    if (g_running != nullptr) g_running->request_stop();
}

struct SimArgs {
    std::string board = ENDOTOWER_DEFAULT_BOARD;
    // Set only when given; an empty value ("") turns the board's setting off.
    std::optional<std::string> input, events, out, frames, trace;
    bool realtime = false, realtime_set = false;
    double latency_ms = -1.0;
    std::vector<std::string> regions;  // --region, in order (ids 0, 1, ...)
    int loops = 1;  // --loop N: play the input video N times (toolchain/soak.sh)
};

int usage_error(const std::string& m) {
    std::fprintf(stderr, "endotower sim: %s\n(see 'endotower sim --help')\n", m.c_str());
    return kExitBadInput;
}

bool parse_ms(const std::string& s, double& out) {
    char* end = nullptr;
    out = std::strtod(s.c_str(), &end);
    return !s.empty() && end != nullptr && *end == 0 && out >= 0 && out <= 1000;
}

// Checks that a file can be created at `path` (its directory exists and is writable).
bool check_output(const std::string& what, const std::string& path, std::string& error) {
    if (path.empty()) return true;
    const fs::path dir = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir)) {
        error = "cannot create the directory for the " + what + ": " + dir.string();
        return false;
    }
    return true;
}

}  // namespace

namespace {
void print_sim_help() {
    std::printf(
        "usage: endotower sim [--board FILE] [--input FILE|DIR] [--events TIMELINE]\n"
        "                     [--out VIDEO] [--frames DIR] [--trace FILE] [--realtime]\n"
        "                     [--latency-ms MS] [--region \"x1,y1 x2,y2 x3,y3 ...\"]...\n"
        "                     [--loop N]\n\n"
        "Runs the appliance on a recording: every frame goes through the fixed-latency\n"
        "video path with the analysis overlay, into a video file and/or PNG frames, with\n"
        "a per-frame trace (JSON Lines, docs/trace.md). Prints a latency summary.\n\n"
        "  --board FILE     board description (default %s)\n"
        "  --input PATH     video file (mp4/avi/mkv) or directory of numbered images\n"
        "  --events FILE    timeline of handle button/wheel events\n"
        "  --out VIDEO      output video (.mkv lossless FFV1, .avi MJPG, .mp4 mp4v)\n"
        "  --frames DIR     also write every output frame as DIR/000000.png ...\n"
        "  --trace FILE     per-frame trace, JSON Lines\n"
        "  --realtime       pace at the recording's frame rate on the real clock\n"
        "                   (default: virtual clock, deterministic, as fast as possible)\n"
        "  --latency-ms MS  capture-to-present latency (default: one frame period)\n"
        "  --region POLY    track a tissue region marked on the first frame (its pixels),\n"
        "                   repeatable (ids 0, 1, ...; the timeline's 'region' marks follow);\n"
        "                   the board's analysis.regions sets the method (docs/regions.md);\n"
        "                   a last item overlay=markers|image:PATH|object:cube anchors an\n"
        "                   image (PATH in analysis.regions.media) or a cube to it\n"
        "  --loop N         play the input video N times in a row, time running on (a soak,\n"
        "                   toolchain/soak.sh); with only --trace, no video is written\n\n"
        "Command-line options override the board file. Exit status: 0 done, 1 failed\n"
        "while running, 2 bad usage or input.\n",
        ENDOTOWER_DEFAULT_BOARD);
}
}  // namespace

int run_sim_command(const Args& args) {
    SimArgs a;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        auto value = [&](std::string& dst) -> bool {
            if (i + 1 >= args.size()) return false;
            dst = args[++i];
            return true;
        };
        if (k == "--help" || k == "-h") {
            print_sim_help();
            return kExitOk;
        } else if (k == "--realtime") {
            a.realtime = a.realtime_set = true;
        } else if (k == "--board" || k == "--input" || k == "--events" || k == "--out" ||
                   k == "--frames" || k == "--trace" || k == "--latency-ms" || k == "--region" ||
                   k == "--loop") {
            std::string v;
            if (!value(v)) return usage_error("option " + k + " needs a value");
            if (k == "--board") a.board = v;
            else if (k == "--input") a.input = v;
            else if (k == "--events") a.events = v;
            else if (k == "--out") a.out = v;
            else if (k == "--frames") a.frames = v;
            else if (k == "--trace") a.trace = v;
            else if (k == "--region") a.regions.push_back(v);
            else if (k == "--loop") {
                char* end = nullptr;
                const long n = std::strtol(v.c_str(), &end, 10);
                if (v.empty() || *end != 0 || n < 1 || n > 1000000)
                    return usage_error("--loop needs a count in 1..1000000, got '" + v + "'");
                a.loops = static_cast<int>(n);
            }
            else if (!parse_ms(v, a.latency_ms))
                return usage_error("--latency-ms needs a number of milliseconds in 0..1000, got '" + v + "'");
        } else {
            return usage_error("unknown option '" + k + "'");
        }
    }

    BoardConfig board;
    std::string error;
    if (!load_board(a.board, board, error)) {
        std::fprintf(stderr, "endotower sim: %s\n", error.c_str());
        return kExitBadInput;
    }
    // The command line overrides the board file.
    if (a.input) board.sim_input = *a.input;
    if (a.events) board.sim_events = *a.events;
    if (a.out) board.sim_output = *a.out;
    if (a.frames) board.sim_frames = *a.frames;
    if (a.trace) board.sim_trace = *a.trace;
    if (a.realtime_set) board.sim_realtime = a.realtime;
    if (a.latency_ms >= 0) board.latency_ms = a.latency_ms;
    if (board.sim_input.empty()) return usage_error("no input: give --input or set sim.input in " + a.board);
    if (board.sim_output.empty() && board.sim_frames.empty() && (a.loops == 1 || board.sim_trace.empty()))
        return usage_error("no output: give --out and/or --frames (or set sim.output)");

    std::vector<vision::RegionMark> marks;
    // A region's overlay: its own overlay=KIND, else the board's analysis.regions.overlay.
    vision::RegionOverlay board_overlay;
    vision::parse_region_overlay(board.region_overlay, board_overlay, error);  // checked
    auto region_overlay = [&](const std::string& kind, vision::RegionOverlay& out) {
        if (kind.empty()) {
            out = board_overlay;
            return true;
        }
        if (!vision::parse_region_overlay(kind, out, error)) return false;
        if (out.kind == vision::RegionOverlayKind::kImage && board.region_media.empty()) {
            error = "overlay '" + kind + "': an image needs a media folder (analysis.regions.media or sci.media in " + a.board + ")";
            return false;
        }
        return true;
    };
    for (const std::string& arg : a.regions) {
        // "x1,y1 x2,y2 x3,y3 ... [overlay=KIND]"
        std::string text = arg, kind;
        const std::size_t at = text.find("overlay=");
        if (at != std::string::npos) {
            kind = text.substr(at + 8);
            text.resize(at);
            if (kind.empty() || kind.find(' ') != std::string::npos)
                return usage_error("--region \"" + arg + "\": overlay=KIND must be the last item");
        }
        std::vector<eval::Point2> poly;
        if (!eval::parse_polygon(text, poly, error))
            return usage_error("--region \"" + arg + "\": " + error);
        if (poly.size() > vision::RegionEstimate::kMaxVertices)
            return usage_error("--region \"" + arg + "\": at most 16 vertices");
        vision::RegionMark m{0, static_cast<int>(marks.size()), {}, {}};
        if (!region_overlay(kind, m.overlay)) return usage_error("--region \"" + arg + "\": " + error);
        for (const eval::Point2& p : poly) m.polygon.push_back({p.x, p.y});
        marks.push_back(std::move(m));
    }

    sim::Timeline timeline;
    if (!board.sim_events.empty() && !sim::load_timeline(board.sim_events, timeline, error)) {
        std::fprintf(stderr, "endotower sim: %s\n", error.c_str());
        return kExitBadInput;
    }
    hal::Nanos wall_watchdog_ns = 0;
    // The replay's wall-clock watchdog on a stage call (default 2 s) can be raised where
    // the CPU is emulated: toolchain/cross-test.sh runs the tests under qemu-user, 8-15x
    // slower, where a slow stage is not a hung one. Not a board key: it says what the
    // host is, not what the appliance does.
    if (const char* w = std::getenv("ENDOTOWER_REPLAY_WATCHDOG_MS"); w != nullptr) {
        char* end = nullptr;
        const long ms = std::strtol(w, &end, 10);
        if (end == w || *end != '\0' || ms < 1 || ms > 3600000) {
            std::fprintf(stderr,
                         "endotower sim: ENDOTOWER_REPLAY_WATCHDOG_MS='%s': expected "
                         "milliseconds, 1..3600000\n",
                         w);
            return kExitBadInput;
        }
        wall_watchdog_ns = static_cast<hal::Nanos>(ms) * hal::kMillisecond;
    }
    if (!board.sim_output.empty()) {
        const std::string ext = fs::path(board.sim_output).extension().string();
        if (ext != ".mkv" && ext != ".avi" && ext != ".mp4")
            return usage_error("cannot write video " + board.sim_output + ": unsupported extension '" + ext +
                               "' (use .mkv, .avi or .mp4)");
    }
    if (!check_output("output video", board.sim_output, error) ||
        !check_output("trace", board.sim_trace, error)) {
        std::fprintf(stderr, "endotower sim: %s\n", error.c_str());
        return kExitBadInput;
    }

    // Simulation owns time unless asked for real time.
    std::unique_ptr<hal::Clock> clock;
    if (board.sim_realtime) clock = std::make_unique<system::MonotonicClock>();
    else clock = std::make_unique<sim::VirtualClock>();

    sim::RecordedFrameSource source({board.sim_input, board.sim_fps, 6, a.loops}, *clock);
    if (!source.open()) {
        std::fprintf(stderr, "endotower sim: %s\n", source.error().c_str());
        return kExitBadInput;
    }
    const double fps = source.frame_rate();
    sim::FileSink sink({board.sim_output, board.sim_frames, fps}, *clock);

    app::TraceWriter trace;
    if (!board.sim_trace.empty() && !trace.open(board.sim_trace)) {
        std::fprintf(stderr, "endotower sim: %s\n", trace.error().c_str());
        return kExitBadInput;
    }

    // Timeline region marks: a time mark applies from the first frame at or after it.
    for (const sim::TimelineEntry& e : timeline.entries) {
        if (e.region.empty()) continue;
        vision::RegionMark m{e.frame, static_cast<int>(marks.size()), {}, {}};
        if (!region_overlay(e.overlay, m.overlay)) {
            std::fprintf(stderr, "endotower sim: %s:%d: %s\n", board.sim_events.c_str(), e.line, error.c_str());
            return kExitBadInput;
        }
        if (e.anchor == sim::TimelineEntry::Anchor::kTime)
            m.frame = static_cast<std::int64_t>(std::ceil(static_cast<double>(e.offset_ns) * fps / 1e9 - 1e-6));
        for (const sim::TimelinePoint& p : e.region) m.polygon.push_back({p.x, p.y});
        marks.push_back(std::move(m));
    }
    if (marks.size() > vision::RegionTracker::kMaxRegions)
        return usage_error(std::to_string(marks.size()) + " regions given (--region and the timeline); at most " +
                           std::to_string(vision::RegionTracker::kMaxRegions));

    // Timeline times count from the first frame's capture, which is "now" at start.
    sim::ScriptedInput scripted(timeline, *clock, clock->now(), fps);
    hal::ControlMerge inputs;
    inputs.attach(&scripted);

    // The analysis path, as the board says (the same builder as `endotower run`).
    app::StderrLog log;
    AnalysisChain analysis;
    // The SCI's overlay is drawn with GLES2 (headless EGL on the host); without one the
    // SCI still runs and traces.
    std::unique_ptr<hal::OverlayRenderer> renderer;
    if (board.sci) {
        renderer = gles::create_gles_renderer(error);
        if (!renderer) std::fprintf(stderr, "endotower sim: sci: no overlay renderer: %s\n", error.c_str());
        error.clear();
    }
    if (!analysis.build(board, source.format(), std::move(marks), renderer.get(), log, "sim", error)) {
        std::fprintf(stderr, "endotower sim: %s\n", error.c_str());
        return kExitBadInput;
    }
    app::AnalysisStage* stage = analysis.stage();

    app::PipelineConfig cfg;
    cfg.latency_ns = static_cast<hal::Nanos>(board.latency_ms * 1e6);
    cfg.compose_budget_ns = static_cast<hal::Nanos>(board.compose_budget_ms * 1e6);
    cfg.analysis_timeout_ns = static_cast<hal::Nanos>(board.analysis_timeout_ms * 1e6);
    cfg.analysis_virtual_cost_ns = static_cast<hal::Nanos>(board.analysis_virtual_cost_ms * 1e6);
    cfg.max_overlay_age = board.max_overlay_age;
    cfg.late_tolerance_ns = static_cast<hal::Nanos>(board.late_tolerance_ms * 1e6);
    if (wall_watchdog_ns > 0) cfg.analysis_wall_timeout_ns = wall_watchdog_ns;
    // Wake at the due time, not up to 50 us after it (the default timer slack).
    if (board.sim_realtime) system::tighten_timer_slack();

    app::Pipeline pipeline(cfg, source, sink, *clock, &inputs, stage,
                           board.sim_trace.empty() ? nullptr : &trace, log);
    g_running = &pipeline;
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    const app::PipelineSummary s = pipeline.run();
    g_running = nullptr;

    if (!source.warning().empty()) std::fprintf(stderr, "endotower sim: warning: %s\n", source.warning().c_str());
    for (const std::string& e : analysis.regions().errors()) std::fprintf(stderr, "endotower sim: cannot mark a region: %s\n", e.c_str());
    const bool trace_ok = board.sim_trace.empty() || trace.close();
    if (!trace_ok) std::fprintf(stderr, "endotower sim: %s\n", trace.error().c_str());

    auto ms = [](hal::Nanos v) { return static_cast<double>(v) / 1e6; };
    std::printf("endotower sim: %lld frames in, %lld out, %lld late, %lld passthrough, %lld analysed\n",
                static_cast<long long>(s.frames_in), static_cast<long long>(s.frames_out),
                static_cast<long long>(s.late_frames), static_cast<long long>(s.passthrough_frames),
                static_cast<long long>(s.analysed_frames));
    std::printf("latency (capture -> present): target %.3f ms; min %.3f, median %.3f, p99 %.3f, max %.3f ms\n",
                ms(s.latency_target_ns), ms(s.latency_min_ns), ms(s.latency_median_ns),
                ms(s.latency_p99_ns), ms(s.latency_max_ns));
    const double media_s = static_cast<double>(s.media_duration_ns) / 1e9;
    std::printf("replay: %.2f s of video in %.2f s wall (%.1fx real time), %s clock\n", media_s,
                s.wall_seconds, s.wall_seconds > 0 ? media_s / s.wall_seconds : 0.0,
                board.sim_realtime ? "real" : "virtual");
    if (s.format_changes > 0 || s.faults > 0 || s.source_gaps > 0)
        std::printf("events: %lld format changes, %lld analysis faults, %lld frames missing at the source\n",
                    static_cast<long long>(s.format_changes), static_cast<long long>(s.faults),
                    static_cast<long long>(s.source_gaps));
    if (!board.sim_output.empty()) std::printf("video: %s\n", board.sim_output.c_str());
    if (!board.sim_frames.empty()) std::printf("frames: %s/\n", board.sim_frames.c_str());
    if (!board.sim_trace.empty() && trace_ok)
        std::printf("trace: %s (%ld lines)\n", board.sim_trace.c_str(), trace.lines());
    if (!s.ok) {
        std::fprintf(stderr, "endotower sim: %s\n", s.error.c_str());
        return kExitFailure;
    }
    if (!trace_ok) return kExitFailure;
    // A region that could not be marked is bad input (a polygon without texture, outside the frame).
    return analysis.regions().errors().empty() ? kExitOk : kExitBadInput;
}

}  // namespace endotower::firmware
