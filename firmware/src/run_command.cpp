// endotower run: the appliance on real devices. The board file names the capture
// device, the handle, the display; the app's Pipeline does the rest.
#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <thread>

#include "analysis_chain.hpp"
#include "board_config.hpp"
#include "endotower/gles/gles_renderer.hpp"
#include "commands.hpp"
#include "devices.hpp"
#include "endotower/app/no_signal_source.hpp"
#include "endotower/app/pipeline.hpp"
#include "endotower/app/trace_writer.hpp"
#include "endotower/hal/control_merge.hpp"
#include "endotower/system/monotonic_clock.hpp"
#include "endotower/system/syscall.hpp"
#include "endotower/usb/usb_hotplug.hpp"

namespace endotower::firmware {

namespace {

constexpr const char* kDefaultBoard = "/etc/endotower/board.yaml";

app::Pipeline* g_pipeline = nullptr;
extern "C" void on_run_signal(int) {
    if (g_pipeline != nullptr) g_pipeline->request_stop();
}

int run_usage(const std::string& m) {
    std::fprintf(stderr, "endotower run: %s\n(see 'endotower run --help')\n", m.c_str());
    return kExitBadInput;
}

void print_run_help() {
    std::printf(
        "usage: endotower run [--board FILE] [--trace FILE] [--seconds S]\n\n"
        "The appliance: live video from the board's capture device to its monitor at a\n"
        "fixed latency, with the analysis overlay; the handle's button and wheel drive it.\n"
        "A 'NO SIGNAL' screen shows while the capture input is silent.\n\n"
        "  --board FILE   board description (default %s)\n"
        "  --trace FILE   per-frame trace, JSON Lines (docs/trace.md)\n"
        "  --seconds S    stop after S seconds (default: until SIGINT/SIGTERM)\n\n"
        "Exit status: 0 stopped, 1 failed while running, 2 bad usage, board file or device\n"
        "(the message names the device and the fix).\n",
        kDefaultBoard);
}

}  // namespace

int run_run_command(const Args& args) {
    std::string board_path = kDefaultBoard, trace_path;
    double seconds = 0;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& k = args[i];
        if (k == "--help" || k == "-h") {
            print_run_help();
            return kExitOk;
        }
        if (k != "--board" && k != "--trace" && k != "--seconds")
            return run_usage("unknown option '" + k + "'");
        if (i + 1 >= args.size()) return run_usage("option " + k + " needs a value");
        const std::string& v = args[++i];
        if (k == "--board")
            board_path = v;
        else if (k == "--trace")
            trace_path = v;
        else {
            char* end = nullptr;
            seconds = std::strtod(v.c_str(), &end);
            if (v.empty() || *end != 0 || seconds <= 0)
                return run_usage("--seconds needs a positive number, got '" + v + "'");
        }
    }

    BoardConfig board;
    std::string error;
    if (!load_board(board_path, board, error)) {
        std::fprintf(stderr, "endotower run: %s\n", error.c_str());
        return kExitBadInput;
    }
    if (!board.capture.present)
        return run_usage(board_path + ": no 'capture:' section: which device is the camera?");

    system::MonotonicClock clock;
    // Probe the camera before anything else: a wrong path, a permission or a format
    // the device does not offer is a configuration error (exit 2), not a run failure.
    v4l2::V4l2Capture capture(capture_config(board));
    if (!capture.start()) {
        print_device_error("run", capture.error(), board_path);
        return kExitBadInput;
    }
    capture.stop();

    display::KmsSink sink(display_config(board), clock);
    if (!sink.open()) {
        print_device_error("run", sink.error(), board_path);
        return kExitBadInput;
    }
    std::printf("endotower run: %s on %s %s (%s commits)\n", board.capture.device.c_str(),
                sink.connector_name().c_str(), sink.mode_name().c_str(),
                sink.atomic() ? "atomic" : "legacy");
    std::fflush(stdout);

    hal::ControlMerge inputs;
    std::unique_ptr<hid::HidHandle> handle;
    if (board.handle.present) {
        handle = std::make_unique<hid::HidHandle>(handle_config(board));
        if (!handle->start(error)) {
            print_device_error("run", error, board_path);
            return kExitBadInput;
        }
        if (!handle->connected())
            std::fprintf(stderr, "endotower run: handle not connected yet: %s\n",
                         handle->last_error().c_str());
        inputs.attach(handle.get());
    }
    // USB arrivals reopen the handle at once; without libusb hotplug the handle still
    // finds its /dev/hidraw node again by itself.
    std::unique_ptr<usb::UsbHotplug> hotplug;
    if (handle) {
        hotplug = std::make_unique<usb::UsbHotplug>(static_cast<std::uint16_t>(board.handle.vid),
                                                    static_cast<std::uint16_t>(board.handle.pid));
        hid::HidHandle* h = handle.get();
        if (!hotplug->start(
                [h](bool arrived) {
                    if (arrived) h->notify_arrival();
                },
                error)) {
            std::fprintf(stderr,
                         "endotower run: USB hotplug unavailable (%s); the handle reconnects "
                         "through /dev/hidraw\n",
                         error.c_str());
            hotplug.reset();
        }
    }
    std::unique_ptr<gpio::GpioButton> button;
    if (board.button.present) {
        button = std::make_unique<gpio::GpioButton>(button_config(board));
        if (!button->start(error)) {
            print_device_error("run", error, board_path);
            return kExitBadInput;
        }
        inputs.attach(button.get());
    }

    app::TraceWriter trace;
    if (!trace_path.empty() && !trace.open(trace_path)) {
        std::fprintf(stderr, "endotower run: %s\n", trace.error().c_str());
        return kExitBadInput;
    }

    // The analysis path, as the board says (the same builder as `endotower sim`).
    app::StderrLog log;
    AnalysisChain analysis;
    // The SCI's overlay is drawn with GLES2 (headless EGL on the host); without one the
    // SCI still runs and traces.
    std::unique_ptr<hal::OverlayRenderer> renderer;
    if (board.sci) {
        renderer = gles::create_gles_renderer(error);
        if (!renderer) std::fprintf(stderr, "endotower run: sci: no overlay renderer: %s\n", error.c_str());
        error.clear();
    }
    hal::FrameFormat input{};
    input.width = board.capture.width, input.height = board.capture.height;
    if (!analysis.build(board, input, {}, renderer.get(), log, "run", error)) {
        std::fprintf(stderr, "endotower run: %s\n", error.c_str());
        return kExitBadInput;
    }

    app::PipelineConfig cfg;
    cfg.latency_ns = static_cast<hal::Nanos>(board.latency_ms * 1e6);
    cfg.compose_budget_ns = static_cast<hal::Nanos>(board.compose_budget_ms * 1e6);
    cfg.analysis_timeout_ns = static_cast<hal::Nanos>(board.analysis_timeout_ms * 1e6);
    cfg.max_overlay_age = board.max_overlay_age;
    cfg.late_tolerance_ns = static_cast<hal::Nanos>(board.late_tolerance_ms * 1e6);
    system::tighten_timer_slack();

    app::NoSignalSource source(capture, clock, log);
    app::Pipeline pipeline(cfg, source, sink, clock, &inputs, analysis.stage(),
                           trace_path.empty() ? nullptr : &trace, log);
    g_pipeline = &pipeline;
    std::signal(SIGINT, on_run_signal);
    std::signal(SIGTERM, on_run_signal);
    std::atomic<bool> done{false};
    std::thread timer;
    if (seconds > 0)
        timer = std::thread([&] {
            const auto until =
                std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
            while (!done.load() && std::chrono::steady_clock::now() < until)
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
            pipeline.request_stop();
        });
    auto cpu_ns = [] {
        rusage u{};
        getrusage(RUSAGE_SELF, &u);
        return (u.ru_utime.tv_sec + u.ru_stime.tv_sec) * hal::kSecond +
               (u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1000;
    };
    const hal::Nanos cpu0 = cpu_ns();
    const app::PipelineSummary s = pipeline.run();
    const hal::Nanos cpu = cpu_ns() - cpu0;
    done = true;
    if (timer.joinable()) timer.join();
    g_pipeline = nullptr;
    const bool trace_ok = trace_path.empty() || trace.close();

    auto ms = [](hal::Nanos v) { return static_cast<double>(v) / 1e6; };
    const v4l2::CaptureStats& cs = capture.stats();
    const display::KmsSinkStats& ds = sink.stats();
    std::printf(
        "endotower run: %lld frames in, %lld out, %lld late; capture: %llu dropped by the driver, "
        "%llu superseded, %llu timeouts, %llu format changes, %llu reopens, %llu corrupt\n",
        static_cast<long long>(s.frames_in), static_cast<long long>(s.frames_out),
        static_cast<long long>(s.late_frames), static_cast<unsigned long long>(cs.drops),
        static_cast<unsigned long long>(cs.skipped), static_cast<unsigned long long>(cs.timeouts),
        static_cast<unsigned long long>(cs.format_changes),
        static_cast<unsigned long long>(cs.reopens), static_cast<unsigned long long>(cs.corrupt));
    std::printf(
        "latency (capture -> page flip): target %.3f ms; min %.3f, median %.3f, p99 %.3f, max %.3f "
        "ms\n",
        ms(s.latency_target_ns), ms(s.latency_min_ns), ms(s.latency_median_ns),
        ms(s.latency_p99_ns), ms(s.latency_max_ns));
    std::printf(
        "display: %lld zero-copy, %lld copied (mean copy %.3f ms, max %.3f ms), %lld dropped "
        "unplugged\n",
        static_cast<long long>(ds.zero_copy_frames), static_cast<long long>(ds.copied_frames),
        ds.copied_frames > 0 ? ms(ds.copy_ns_total) / static_cast<double>(ds.copied_frames) : 0.0,
        ms(ds.copy_ns_max), static_cast<long long>(ds.dropped_frames));
    std::printf("cpu: %.3f ms per frame shown (user + system, every thread)\n",
                s.frames_out > 0 ? ms(cpu) / static_cast<double>(s.frames_out) : 0.0);
    std::printf("overlay: %lld frames drawn with GLES2 (mean %.3f ms, max %.3f ms)\n",
                static_cast<long long>(ds.overlay_frames),
                ds.overlay_frames > 0
                    ? ms(ds.overlay_ns_total) / static_cast<double>(ds.overlay_frames)
                    : 0.0,
                ms(ds.overlay_ns_max));
    if (!s.ok) {
        std::fprintf(stderr, "endotower run: %s\n", s.error.c_str());
        return kExitFailure;
    }
    return trace_ok ? kExitOk : kExitFailure;
}

}  // namespace endotower::firmware
