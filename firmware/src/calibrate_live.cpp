#include "calibrate_live.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "board_config.hpp"
#include "devices.hpp"
#include "endotower/sim/recorded_source.hpp"
#include "endotower/sim/virtual_clock.hpp"
#include "endotower/system/syscall.hpp"
#include "endotower/v4l2/v4l2_capture.hpp"

namespace endotower::firmware {

namespace {

using namespace endotower::calibration;

// Mean distance between corresponding corners; infinite when the counts differ.
double corner_shift(const View& a, const View& b) {
    if (a.image_points.size() != b.image_points.size() || a.image_points.empty()) return INFINITY;
    double s = 0;
    for (std::size_t i = 0; i < a.image_points.size(); ++i)
        s += std::hypot(a.image_points[i].x - b.image_points[i].x,
                        a.image_points[i].y - b.image_points[i].y);
    return s / static_cast<double>(a.image_points.size());
}

bool save_view(const std::string& dir, const GrayImage& g, int index, std::string& error) {
    const cv::Mat m(g.height, g.width, CV_8UC1, const_cast<std::uint8_t*>(g.pixels.data()));
    std::vector<std::uint8_t> png;
    if (!cv::imencode(".png", m, png)) {
        error = "cannot encode view " + std::to_string(index) + " as PNG";
        return false;
    }
    char name[32];
    std::snprintf(name, sizeof name, "view_%02d.png", index);
    return system::write_file_atomic((std::filesystem::path(dir) / name).string(),
                                     std::string(png.begin(), png.end()), error);
}

}  // namespace

bool capture_live_views(const LiveViewOptions& o, const TargetSpec& target, LiveViews& out,
                        std::string& error) {
    BoardConfig board;
    if (!load_board(o.board, board, error)) return false;
    sim::VirtualClock clock;
    std::unique_ptr<hal::FrameSource> source;
    const bool live = board.capture.present;
    if (live) {
        source = std::make_unique<v4l2::V4l2Capture>(capture_config(board));
        out.source = board.capture.device;
    } else if (!board.sim_input.empty()) {
        auto rec = std::make_unique<sim::RecordedFrameSource>(
            sim::RecordedSourceOptions{board.sim_input, board.sim_fps, 4}, clock);
        if (!rec->open()) {
            error = rec->error();
            return false;
        }
        source = std::move(rec);
        out.source = board.sim_input;
    } else {
        error = o.board + ": the board has no camera (no capture: and no sim.input)";
        return false;
    }
    if (!source->start()) {
        error = source->error();
        const std::string fix = live ? device_fix(error, o.board) : "";
        if (!fix.empty()) error += "\n  fix: " + fix;
        return false;
    }
    if (!o.save_dir.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(o.save_dir, ec);
        if (ec) {
            error = "cannot create " + o.save_dir + ": " + ec.message();
            source->stop();
            return false;
        }
    }
    const auto t0 = std::chrono::steady_clock::now();
    auto last_report = t0;
    hal::Nanos last_try = INT64_MIN / 2;
    long found = 0;
    bool ok = true;
    while (static_cast<int>(out.views.size()) < o.views) {
        const double waited =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (live && waited > o.timeout_s) {
            std::printf("calibrate: %.0f s without the %d views asked for: going on with %zu\n",
                        waited, o.views, out.views.size());
            break;
        }
        if (std::chrono::steady_clock::now() - last_report > std::chrono::seconds(3)) {
            std::printf("calibrate: %ld frames, the target found in %ld, %zu of %d views kept\n",
                        out.frames, found, out.views.size(), o.views);
            std::fflush(stdout);
            last_report = std::chrono::steady_clock::now();
        }
        hal::Frame f;
        const hal::SourceStatus st = source->next(f, 1'000'000'000);
        if (st == hal::SourceStatus::kEndOfStream) {
            std::printf("calibrate: end of %s after %ld frames: %zu views kept\n",
                        out.source.c_str(), out.frames, out.views.size());
            break;
        }
        if (st == hal::SourceStatus::kTimeout || st == hal::SourceStatus::kFormatChange) continue;
        if (st == hal::SourceStatus::kError) {
            error = source->error();
            ok = false;
            break;
        }
        ++out.frames;
        const bool due =
            f.capture_ns - last_try >= static_cast<hal::Nanos>(o.min_interval_ms * 1e6);
        GrayImage g;
        const bool converted = due && gray_from_frame(f, g);
        const std::uint64_t seq = f.sequence;
        source->release(f);
        if (!converted) continue;
        last_try = f.capture_ns;
        if (!out.images.empty() &&
            (g.width != out.images.front().width || g.height != out.images.front().height)) {
            std::printf("calibrate: frame %llu is %dx%d, the kept views %dx%d: skipped\n",
                        static_cast<unsigned long long>(seq), g.width, g.height,
                        out.images.front().width, out.images.front().height);
            continue;
        }
        g.name = "frame " + std::to_string(seq);
        View v;
        std::string why;
        if (!detect_target(g, target, v, why)) continue;
        ++found;
        double nearest = INFINITY;
        for (const View& k : out.views) nearest = std::min(nearest, corner_shift(v, k));
        if (nearest < o.novelty * g.width) continue;  // the same view again: move the target
        const int index = static_cast<int>(out.views.size()) + 1;
        if (!o.save_dir.empty() && !save_view(o.save_dir, g, index, error)) {
            ok = false;
            break;
        }
        std::printf("calibrate: view %d/%d kept: %s, %zu points\n", index, o.views, g.name.c_str(),
                    v.image_points.size());
        std::fflush(stdout);
        out.views.push_back(std::move(v));
        out.images.push_back(std::move(g));
    }
    source->stop();
    return ok;
}

}  // namespace endotower::firmware
