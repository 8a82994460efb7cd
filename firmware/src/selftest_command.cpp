// endotower selftest: the service technician's check of a board, with a test
// pattern and prompts on the monitor and a report in text and JSON (docs/selftest.md).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <thread>

#include "board_config.hpp"
#include "commands.hpp"
#include "devices.hpp"
#include "endotower/app/pipeline.hpp"
#include "endotower/app/test_pattern_stage.hpp"
#include "endotower/hal/control_merge.hpp"
#include "endotower/system/monotonic_clock.hpp"
#include "endotower/system/syscall.hpp"
#include "selftest_checks.hpp"

namespace endotower::firmware {

namespace {

using R = Check::Result;
using Clock = std::chrono::steady_clock;

struct SelftestArgs {
    std::string board = "/etc/endotower/board.yaml";
    std::string report;  // default: the board's storage directory, else "."
    int frames = 300;
    double input_timeout_s = 30;
};

int selftest_usage(const std::string& m) {
    std::fprintf(stderr, "endotower selftest: %s\n(see 'endotower selftest --help')\n", m.c_str());
    return kExitBadInput;
}

// Records what the technician did with one input, forwarding its events.
class WatchedInput final : public hal::ControlInput {
public:
    explicit WatchedInput(hal::ControlInput& in) : in_(in) {}
    bool poll(hal::ControlEvent& e) override {
        if (!in_.poll(e)) return false;
        if (e.kind == hal::ControlEvent::Kind::kButtonPress) pressed = true;
        if (e.kind == hal::ControlEvent::Kind::kButtonRelease && pressed) released = true;
        if (e.kind == hal::ControlEvent::Kind::kWheel) wheel += e.delta;
        return true;
    }
    std::atomic<bool> pressed{false}, released{false};
    std::atomic<int> wheel{0};

private:
    hal::ControlInput& in_;
};

// The display as the pipeline sees it, measuring capture -> page-flip latency and the
// camera's frame rate (from its sequence numbers and kernel timestamps). The first
// kWarmup frames are not counted: they carry the mode set and the shader compilation.
class ProbeSink final : public hal::VideoSink {
public:
    ProbeSink(hal::VideoSink& in, int n) : in_(in) {
        latency_.reserve(static_cast<std::size_t>(n)), n_ = n;
    }
    bool configure(const hal::FrameFormat& f) override { return in_.configure(f); }
    hal::Nanos present(const hal::Frame& v, const hal::OverlayLayer* o, hal::Nanos due) override {
        const hal::Nanos t = in_.present(v, o, due);
        if (t > 0 && ++seen_ <= kWarmup) return t;
        if (t > 0 && static_cast<int>(latency_.size()) < n_) {
            latency_.push_back(t - v.capture_ns);
            if (latency_.size() == 1) first_seq_ = v.sequence, first_ns_ = v.capture_ns;
            last_seq_ = v.sequence, last_ns_ = v.capture_ns;
            count_.store(static_cast<int>(latency_.size()));
        }
        return t;
    }
    bool finish() override { return in_.finish(); }
    const std::string& error() const override { return in_.error(); }
    int count() const { return count_.load(); }
    std::vector<hal::Nanos> latencies() const { return latency_; }
    double frame_rate() const {
        return last_ns_ > first_ns_ ? static_cast<double>(last_seq_ - first_seq_) * 1e9 /
                                          static_cast<double>(last_ns_ - first_ns_)
                                    : 0;
    }

    static constexpr int kWarmup = 5;

private:
    hal::VideoSink& in_;
    int n_ = 0, seen_ = 0;
    std::vector<hal::Nanos> latency_;
    std::atomic<int> count_{0};
    std::uint64_t first_seq_ = 0, last_seq_ = 0;
    hal::Nanos first_ns_ = 0, last_ns_ = 0;
};

// A BGRA frame of colour bars at the mode's size: what the monitor shows before
// (and without) the camera.
struct PatternFrame {
    std::vector<std::uint8_t> px;
    hal::Frame frame;
    PatternFrame(int w, int h) {
        frame.format = {w, h, 4 * w, hal::PixelFormat::kBgra32};
        px.resize(frame.format.size_bytes());
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const app::Rgba c = app::TestPatternStage::kBars[x * 8 / w];
                std::uint8_t* p = &px[(static_cast<std::size_t>(y) * w + x) * 4];
                p[0] = c.b, p[1] = c.g, p[2] = c.r, p[3] = 255;
            }
        frame.data = px.data();
    }
};

std::string fmt(const char* f, double a, double b = 0, double c = 0, double d = 0) {
    char buf[256];
    std::snprintf(buf, sizeof buf, f, a, b, c, d);
    return buf;
}

}  // namespace

int run_selftest_command(const Args& args) {
    SelftestArgs a;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        if (k == "--help" || k == "-h") {
            std::printf(
                "usage: endotower selftest [--board FILE] [--report DIR] [--frames N] "
                "[--input-timeout S]\n\n"
                "Checks a board for service: camera present, signal, format and frame rate; the\n"
                "handle's button and wheel and the GPIO button (prompted on the monitor and "
                "here);\n"
                "display connected and mode set; capture -> page-flip latency over N frames;\n"
                "calibration and gesture-model files; storage writable. A test pattern shows on\n"
                "the monitor meanwhile. One PASS/FAIL/SKIP line per check; DIR/selftest.txt and\n"
                "DIR/selftest.json (default DIR: the board's paths.storage). docs/selftest.md.\n\n"
                "  --board FILE        board description (default %s)\n"
                "  --frames N          frames for the latency and frame-rate checks (default 300)\n"
                "  --input-timeout S   seconds to wait for each button/wheel action (default "
                "30)\n\n"
                "Exit status: 0 every check passed, 1 a check failed, 2 bad usage or board file.\n",
                a.board.c_str());
            return kExitOk;
        }
        if (k != "--board" && k != "--report" && k != "--frames" && k != "--input-timeout")
            return selftest_usage("unknown option '" + k + "'");
        if (i + 1 >= args.size()) return selftest_usage("option " + k + " needs a value");
        const std::string& v = args[++i];
        char* end = nullptr;
        if (k == "--board")
            a.board = v;
        else if (k == "--report")
            a.report = v;
        else if (k == "--frames") {
            const long n = std::strtol(v.c_str(), &end, 10);
            if (v.empty() || *end != 0 || n < 10 || n > 100000)
                return selftest_usage("--frames needs 10..100000, got '" + v + "'");
            a.frames = static_cast<int>(n);
        } else {
            a.input_timeout_s = std::strtod(v.c_str(), &end);
            if (v.empty() || *end != 0 || a.input_timeout_s < 0 || a.input_timeout_s > 3600)
                return selftest_usage("--input-timeout needs 0..3600 seconds, got '" + v + "'");
        }
    }
    BoardConfig board;
    std::string error;
    if (!load_board(a.board, board, error)) {
        std::fprintf(stderr, "endotower selftest: %s\n", error.c_str());
        return kExitBadInput;
    }
    if (a.report.empty()) a.report = board.storage.empty() ? "." : board.storage;

    SelftestReport report;
    report.board = a.board;
    report.board_name = board.name;
    report.started_unix = static_cast<long long>(std::time(nullptr));
    auto add = [&](Check c) {
        std::printf("%s\n", report.line(c).c_str());
        std::fflush(stdout);
        report.checks.push_back(std::move(c));
    };
    auto fail_fix = [&](const std::string& e) {
        const std::string fix = device_fix(e, a.board);
        return fix.empty() ? e : e + "; fix: " + fix;
    };
    std::printf("endotower selftest: board %s (%s)\n", board.name.c_str(), a.board.c_str());

    add(check_storage(board.storage));
    add(check_calibration(board.calibration));
    add(check_gesture_model(board.gesture_model));
    add(check_gesture_pixel_model(board.gesture_tool_model));

    // Display first: the test pattern shows while everything else is checked.
    system::MonotonicClock clock;
    display::KmsSink sink(display_config(board), clock);
    const std::vector<std::string> prompts = {
        "CHECKING CAMERA AND LATENCY - PLEASE WAIT", "PRESS AND RELEASE THE HANDLE BUTTON",
        "TURN THE HANDLE WHEEL", "PRESS AND RELEASE THE GPIO BUTTON", "DONE"};
    app::TestPatternStage pattern(prompts);
    bool display_ok = sink.open();
    std::unique_ptr<PatternFrame> still;
    app::OverlayCanvas canvas;
    auto show_still = [&](int prompt) {  // the pattern without the camera
        if (!display_ok || !still) return hal::Nanos{-1};
        canvas.clear();
        app::JsonLine trace;
        trace.begin_object();
        app::AnalysisContext ctx{still->frame, {}, canvas, trace, 0};
        pattern.set_prompt(prompt);
        pattern.process(ctx);
        return sink.present(still->frame, &canvas.layer(), clock.now());
    };
    if (!display_ok) {
        add({"display connected", R::kFail, fail_fix(sink.error())});
        add({"display mode set", R::kSkip, "no display"});
    } else {
        add({"display connected", R::kPass, board.display_card + " " + sink.connector_name()});
        still = std::make_unique<PatternFrame>(board.display_width, board.display_height);
        canvas.configure(board.display_width, board.display_height);
        pattern.configure(still->frame.format);
        const bool shown = sink.configure(still->frame.format) && show_still(0) > 0;
        add({"display mode set", shown ? R::kPass : R::kFail,
             shown ? sink.mode_name() + (sink.atomic() ? ", atomic" : ", legacy") +
                         ", test pattern shown"
                   : sink.error()});
        display_ok = shown;
    }

    // Inputs, watched while the pipeline (or the prompt loop) polls them.
    hal::ControlMerge merge;
    std::unique_ptr<hid::HidHandle> handle;
    std::unique_ptr<WatchedInput> handle_watch;
    if (board.handle.present) {
        handle = std::make_unique<hid::HidHandle>(handle_config(board));
        if (!handle->start(error)) {
            add({"handle present", R::kFail, fail_fix(error)});
            handle.reset();
        } else {
            // hidapi opens it from its own thread: give it a moment.
            for (int i = 0; i < 40 && !handle->connected(); ++i)
                std::this_thread::sleep_for(std::chrono::milliseconds(50));
            if (handle->connected()) {
                char ids[32];
                std::snprintf(ids, sizeof ids, "HID %04x:%04x", board.handle.vid, board.handle.pid);
                add({"handle present", R::kPass, ids});
                handle_watch = std::make_unique<WatchedInput>(*handle);
                merge.attach(handle_watch.get());
            } else {
                add({"handle present", R::kFail,
                     fail_fix(handle->last_error()) + "; fix: plug the handle in"});
            }
        }
    }

    std::unique_ptr<gpio::GpioButton> button;
    std::unique_ptr<WatchedInput> button_watch;
    if (board.button.present) {
        button = std::make_unique<gpio::GpioButton>(button_config(board));
        if (!button->start(error)) {
            add({"gpio button present", R::kFail, fail_fix(error)});
            button.reset();
        } else {
            add({"gpio button present", R::kPass,
                 board.button.chip + " line " + std::to_string(board.button.line)});
            button_watch = std::make_unique<WatchedInput>(*button);
            merge.attach(button_watch.get());
        }
    }

    // Camera.
    bool camera_ok = false;
    hal::FrameFormat cam_format{};
    hal::Nanos period = 0;
    std::unique_ptr<v4l2::V4l2Capture> capture;
    if (!board.capture.present) {
        add({"camera present", R::kSkip, "no capture: section in the board file"});
    } else {
        capture = std::make_unique<v4l2::V4l2Capture>(capture_config(board));
        if (!capture->start()) {
            add({"camera present", R::kFail, fail_fix(capture->error())});
        } else {
            add({"camera present", R::kPass, board.capture.device});
            hal::Frame f;
            hal::SourceStatus st = hal::SourceStatus::kTimeout;
            for (int i = 0;
                 i < 3 && st != hal::SourceStatus::kFrame && st != hal::SourceStatus::kError; ++i) {
                st = capture->next(f, hal::kSecond);
                if (st == hal::SourceStatus::kFormatChange) st = hal::SourceStatus::kTimeout;
            }
            if (st == hal::SourceStatus::kFrame) capture->release(f);
            cam_format = capture->format();
            period = capture->frame_period();
            add({"camera signal", st == hal::SourceStatus::kFrame ? R::kPass : R::kFail,
                 st == hal::SourceStatus::kFrame
                     ? "frames arriving"
                     : "no frame in 3 s; fix: check the video source is on and its cable"});
            const bool fmt_ok =
                cam_format.pixel_format == v4l2::info(capture_config(board).format).pixel &&
                (!board.capture.dv_timings.empty() || (cam_format.width == board.capture.width &&
                                                       cam_format.height == board.capture.height));
            add({"camera format", fmt_ok ? R::kPass : R::kFail,
                 std::to_string(cam_format.width) + "x" + std::to_string(cam_format.height) + " " +
                     std::string(hal::to_string(cam_format.pixel_format)) +
                     fmt(", %.2f Hz nominal", period > 0 ? 1e9 / static_cast<double>(period) : 0) +
                     (fmt_ok ? "" : "; board file asks for " + board.capture.format)});
            camera_ok = st == hal::SourceStatus::kFrame;
            capture->stop();
        }
    }

    struct Prompt {
        int index;
        WatchedInput* input;
        const char* check;
        bool wheel;
    };
    std::vector<Prompt> wanted;
    if (handle_watch) {
        wanted.push_back({1, handle_watch.get(), "handle button", false});
        wanted.push_back({2, handle_watch.get(), "handle wheel", true});
    }
    if (button_watch) wanted.push_back({3, button_watch.get(), "gpio button", false});
    auto seen = [](const Prompt& p) {
        return p.wheel ? p.input->wheel.load() != 0
                       : p.input->pressed.load() && p.input->released.load();
    };
    auto ask = [&](const Prompt& p) {
        std::printf(">>> %s (%.0f s)\n", prompts[static_cast<std::size_t>(p.index)].c_str(),
                    a.input_timeout_s);
        std::fflush(stdout);
        pattern.set_prompt(p.index);
    };
    std::vector<Check> input_checks;
    auto record_input = [&](const Prompt& p, bool ok) {
        input_checks.push_back(
            {p.check, ok ? R::kPass : R::kFail,
             ok ? (p.wheel ? "wheel turned " + std::to_string(p.input->wheel.load()) + " detents"
                           : "pressed and released")
                : fmt("nothing within %.0f s", a.input_timeout_s)});
    };

    if (camera_ok && display_ok) {
        // Live video with the pattern over it, through the appliance's own pipeline.
        ProbeSink probe(sink, a.frames);
        app::PipelineConfig cfg;
        cfg.latency_ns = static_cast<hal::Nanos>(board.latency_ms * 1e6);
        cfg.compose_budget_ns = static_cast<hal::Nanos>(board.compose_budget_ms * 1e6);
        cfg.late_tolerance_ns = static_cast<hal::Nanos>(board.late_tolerance_ms * 1e6);
        system::tighten_timer_slack();
        app::StderrLog log;
        pattern.set_prompt(0);
        app::Pipeline pipeline(cfg, *capture, probe, clock, &merge, &pattern, nullptr, log);
        std::thread controller([&] {
            // Generous: a real board shows 300 frames in 5 s; an emulated one needs ~1 s each.
            const auto limit = Clock::now() + std::chrono::seconds(20 + a.frames);
            while (probe.count() < a.frames && Clock::now() < limit)
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
            for (const Prompt& p : wanted) {
                ask(p);
                const auto until = Clock::now() + std::chrono::duration<double>(a.input_timeout_s);
                while (!seen(p) && Clock::now() < until)
                    std::this_thread::sleep_for(std::chrono::milliseconds(20));
                record_input(p, seen(p));
            }
            pattern.set_prompt(4);
            pipeline.request_stop();
        });
        const app::PipelineSummary s = pipeline.run();
        controller.join();
        std::vector<hal::Nanos> lat = probe.latencies();
        const hal::Nanos budget = board.latency_budget_ms > 0
                                      ? static_cast<hal::Nanos>(board.latency_budget_ms * 1e6)
                                      : period + 2 * hal::kMillisecond;
        if (lat.size() < 10) {
            add({"frame rate", R::kFail,
                 "too few frames shown (" + std::to_string(lat.size()) + "): " + s.error});
            add({"latency", R::kFail, "too few frames shown"});
        } else {
            const double rate = probe.frame_rate(),
                         nominal = period > 0 ? 1e9 / static_cast<double>(period) : 0;
            const bool rate_ok = nominal > 0 && std::abs(rate - nominal) <= 0.02 * nominal;
            add({"frame rate", rate_ok ? R::kPass : R::kFail,
                 fmt("%.2f Hz measured from kernel timestamps, %.2f Hz nominal (within 2 %%)", rate,
                     nominal)});
            std::sort(lat.begin(), lat.end());
            auto q = [&](double p) {
                return static_cast<double>(
                           lat[static_cast<std::size_t>(p * static_cast<double>(lat.size() - 1))]) /
                       1e6;
            };
            const bool lat_ok = lat.front() > 0 && q(0.99) <= static_cast<double>(budget) / 1e6;
            add({"latency", lat_ok ? R::kPass : R::kFail,
                 fmt("capture -> page flip over %.0f frames: median %.2f, p99 %.2f, max %.2f ms",
                     static_cast<double>(lat.size()), q(0.5), q(0.99), q(1.0)) +
                     fmt(" (budget %.2f ms)", static_cast<double>(budget) / 1e6)});
        }
    } else {
        add({"frame rate", R::kSkip, "needs the camera and the display"});
        add({"latency", R::kSkip, "needs the camera and the display"});
        // Inputs without video: the pattern stays on the monitor with each prompt.
        for (const Prompt& p : wanted) {
            ask(p);
            show_still(p.index);
            hal::ControlEvent e;
            const auto until = Clock::now() + std::chrono::duration<double>(a.input_timeout_s);
            while (!seen(p) && Clock::now() < until) {
                while (merge.poll(e)) {
                }
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
            }
            record_input(p, seen(p));
        }
        show_still(4);
    }
    for (Check& c : input_checks) add(std::move(c));

    if (!write_report(a.report, report, error)) {
        std::fprintf(stderr, "endotower selftest: cannot write the report: %s\n", error.c_str());
        return kExitFailure;
    }
    std::printf("overall: %s\nreport: %s/selftest.txt, %s/selftest.json\n",
                report.passed() ? "PASS" : "FAIL", a.report.c_str(), a.report.c_str());
    return report.passed() ? kExitOk : kExitFailure;
}

}  // namespace endotower::firmware
