// Overlay render + composite at 1920x1080 with a full menu open (docs/performance.md):
// 12 buttons with text, an 8-item ring menu, a patient-record panel, a 512x512 image,
// the 3-D image box, the cursor and its dwell arc; GlesRenderer on Mesa (llvmpipe
// here). Median and p99 per frame, and heap allocations per frame (the process's,
// Mesa included) in steady state. "CPU" is the whole process (llvmpipe threads too).
// Args: 0 = everything moves every frame (the whole menu shifts by a pixel: nothing
// can be reused, the cold cost); 1 = the menu stands still and the cursor with its
// dwell arc moves over the video; 2 = the cursor moves across the ring menu (that
// rect is drawn again every frame). Layer: transparent at the start of every frame.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "alloc_counter.hpp"
#include "endotower/gles/gles_renderer.hpp"
#include "endotower/vision/anchored_overlay.hpp"

namespace {

using namespace endotower;

hal::OverlayScene full_menu(float shift) {
    hal::OverlayScene s;
    s.camera = {.fx = 937.4, .fy = 925.6, .cx = 973.5, .cy = 530.5};
    auto text = [&](const char* what, float x, float y, float size, hal::SceneText::Align a) {
        hal::SceneText t;
        std::snprintf(t.utf8.data(), t.utf8.size(), "%s", what);
        t.x = x, t.y = y, t.size_px = size, t.align = a, t.colour = {255, 255, 255, 255};
        s.texts.add(t);
    };
    const char* names[12] = {"Preoperative images",
                             "Patient record",
                             "3-D effects",
                             "Exit",
                             "CT",
                             "MRI",
                             "X-ray",
                             "Return",
                             "Image box",
                             "Suture",
                             "Next",
                             "Previous"};
    for (int i = 0; i < 12; ++i) {  // two columns of buttons down the sides
        const float x = (i < 6 ? 40.f : 1600.f) + shift, y = 120.f + float(i % 6) * 120.f;
        s.quads.add({.x = x,
                     .y = y,
                     .width = 280,
                     .height = 90,
                     .corner_px = 14,
                     .border_px = 3,
                     .fill = {30, 30, 30, 170},
                     .border = {255, 255, 255, 230}});
        text(names[i], x + 140, y + 45, 32, hal::SceneText::Align::kCentre);
    }
    for (int i = 0; i < 8; ++i)  // the ring menu around the tool
        s.sectors.add({.cx = 1150 + shift,
                       .cy = 700,
                       .r_inner = 90,
                       .r_outer = 200,
                       .start_deg = float(i * 45),
                       .end_deg = float(i * 45 + 42),
                       .border_px = 2,
                       .fill = {0, 110, 230, 150},
                       .border = {255, 255, 255, 255}});
    s.quads.add({.x = 400 + shift,
                 .y = 40,
                 .width = 560,
                 .height = 200,
                 .corner_px = 10,
                 .fill = {0, 0, 0, 140},
                 .border = {}});
    text("Patient: Anna Muller  ID 0042", 420 + shift, 60, 28, hal::SceneText::Align::kTopLeft);
    text("Born 1971-04-02  Cholecystectomy", 420 + shift, 110, 28, hal::SceneText::Align::kTopLeft);
    text("Notes: allergic to latex", 420 + shift, 160, 28, hal::SceneText::Align::kTopLeft);
    s.images.add(
        {.image_id = 0, .x = 1000 + shift, .y = 60, .width = 400, .height = 400, .opacity = 0.9f});
    hal::SceneBox box;  // the 40 mm image box at 80 mm, turned
    const float c = std::cos(0.5f), sn = std::sin(0.5f);
    box.camera_from_model = {c, 0, -sn, 0, 0, 1, 0, 0, sn, 0, c, 0, -30 + shift / 10, 20, 80, 1};
    box.faces = {{{200, 80, 80, 220},
                  {200, 80, 80, 220},
                  {80, 200, 80, 220},
                  {80, 200, 80, 220},
                  {80, 80, 200, 220},
                  {80, 80, 200, 220}}};
    s.boxes.add(box);
    return s;
}

// The cursor (the tool tip) and its dwell-progress arc.
void cursor(hal::OverlayScene& s, float x, float y, float sweep) {
    s.discs.add({.cx = x, .cy = y, .r_outer = 10, .colour = {255, 255, 0, 255}});
    s.discs.add({.cx = x,
                 .cy = y,
                 .r_inner = 16,
                 .r_outer = 22,
                 .sweep_deg = sweep,
                 .colour = {255, 255, 0, 200}});
}

void BM_RenderFullMenu1080p(benchmark::State& state) {
    constexpr int kW = 1920, kH = 1080;
    std::string error;
    auto renderer = gles::create_gles_renderer(error);
    if (!renderer || !renderer->configure(kW, kH)) {
        state.SkipWithError((renderer ? renderer->error() : error).c_str());
        return;
    }
    std::vector<std::uint8_t> image(512 * 512 * 4);
    for (std::size_t i = 0; i < image.size(); ++i) image[i] = std::uint8_t(i * 7 % 251);
    for (std::size_t i = 3; i < image.size(); i += 4) image[i] = 255;
    if (!renderer->set_image(0, {512, 512, 512 * 4, image.data()})) {
        state.SkipWithError(renderer->error().c_str());
        return;
    }
    const std::array<hal::OverlayScene, 2> menus = {full_menu(0), full_menu(1)};
    hal::OverlayScene scene;
    const std::vector<std::uint8_t> clean(static_cast<std::size_t>(kW) * kH * 4, 0);
    std::vector<std::uint8_t> px = clean;
    int frame = 0;
    // The scene of frame k, built before the clock starts.
    auto next_scene = [&] {
        const int k = frame++;
        const float t = float(k % 120) / 120.f * 6.2832f;
        scene = menus[state.range(0) == 0 ? k % 2 : 0];
        if (state.range(0) == 2)
            cursor(scene, 1150 + 150 * std::cos(t), 700 + 150 * std::sin(t), float(k % 60) * 6);
        else
            cursor(scene, 680 + 80 * std::cos(t), 370 + 80 * std::sin(t), float(k % 60) * 6);
    };
    hal::OverlayLayer layer;
    layer.width = kW, layer.height = kH, layer.stride = 4 * kW, layer.rgba = px.data();
    hal::DrawnRects drawn;
    for (int i = 0; i < 5; ++i) next_scene(), renderer->render(scene, layer, drawn);  // warm up
    std::vector<double> ms;
    ms.reserve(100000);
    std::int64_t frames = 0, allocs = 0;
    for (auto _ : state) {
        state.PauseTiming();
        std::copy(clean.begin(), clean.end(), px.begin());  // a fresh layer each frame
        next_scene();
        state.ResumeTiming();
        const std::int64_t a0 = bench::allocations();
        const auto t0 = std::chrono::steady_clock::now();
        if (!renderer->render(scene, layer, drawn)) {
            state.SkipWithError(renderer->error().c_str());
            return;
        }
        const auto t1 = std::chrono::steady_clock::now();
        allocs += bench::allocations() - a0;
        ++frames;
        ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    std::int64_t area = 0;
    for (std::size_t i = 0; i < drawn.count; ++i)
        area += std::int64_t(drawn.rects[i].width) * drawn.rects[i].height;
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["allocs_per_frame"] = double(allocs) / double(frames);
    state.counters["rects"] = double(drawn.count);
    state.counters["rect_mpix"] = double(area) / 1e6;
}
BENCHMARK(BM_RenderFullMenu1080p)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3);

// An overlay anchored to a tracked region (issue 7) at 1920x1080: the region (a 400x300
// px box marked at the centre) turns by 0.5 degree and shifts by a pixel every frame, so
// nothing is reused; per frame the geometry (anchored_image_corners, or tissue_pose and
// anchored_cube) and the render + composite. Arg 0: a 512x384 image warped onto it;
// arg 1: the cube standing on it. The added per-frame cost of an anchored overlay.
void BM_AnchoredOverlay1080p(benchmark::State& state) {
    constexpr int kW = 1920, kH = 1080;
    std::string error;
    auto renderer = gles::create_gles_renderer(error);
    if (!renderer || !renderer->configure(kW, kH)) {
        state.SkipWithError((renderer ? renderer->error() : error).c_str());
        return;
    }
    std::vector<std::uint8_t> image(512 * 384 * 4);
    for (std::size_t i = 0; i < image.size(); ++i) image[i] = std::uint8_t(i * 7 % 251);
    for (std::size_t i = 3; i < image.size(); i += 4) image[i] = 255;
    if (!renderer->set_image(0, {512, 384, 512 * 4, image.data()})) {
        state.SkipWithError(renderer->error().c_str());
        return;
    }
    vision::RegionEstimate e;
    e.state = vision::RegionState::kTracked, e.vertices = 4;
    e.marked = {{{760, 390}, {1160, 390}, {1160, 690}, {760, 690}}};
    const hal::SceneCamera camera{.fx = 1400, .fy = 1400, .cx = 960, .cy = 540};
    hal::OverlayScene scene;
    scene.camera = camera;
    const std::vector<std::uint8_t> clean(static_cast<std::size_t>(kW) * kH * 4, 0);
    std::vector<std::uint8_t> px = clean;
    hal::OverlayLayer layer;
    layer.width = kW, layer.height = kH, layer.stride = 4 * kW, layer.rgba = px.data();
    hal::DrawnRects drawn;
    std::array<hal::Rgba8, 6> faces;
    faces.fill({90, 200, 255, 220});
    int frame = 0;
    // Frame k's region: rotated about the box's centre, shifted; then the overlay.
    auto anchored_frame = [&]() -> bool {
        const int k = frame++ % 60;
        const double a = k * 0.5 * 3.14159265 / 180, c = std::cos(a), s = std::sin(a);
        e.homography = {c, -s, 960 - c * 960 + s * 540 + k, s, c, 540 - s * 960 - c * 540, 0, 0, 1};
        scene.clear();
        if (state.range(0) == 0) {
            std::array<vision::Point2, 4> q{};
            if (!vision::anchored_image_corners(e, 512, 384, q)) return false;
            hal::SceneImage im;
            im.warped = true;
            for (std::size_t i = 0; i < 4; ++i)
                im.corners[i] = {float(q[i].x + 0.5), float(q[i].y + 0.5)};
            scene.images.add(im);
        } else {
            vision::TissuePose pose;
            if (!vision::tissue_pose(e, camera, 80, pose)) return false;
            scene.boxes.add(vision::anchored_cube(pose, faces));
        }
        return renderer->render(scene, layer, drawn);
    };
    for (int i = 0; i < 5; ++i) anchored_frame();  // warm up
    std::vector<double> ms;
    ms.reserve(100000);
    std::int64_t frames = 0, allocs = 0;
    for (auto _ : state) {
        state.PauseTiming();
        std::copy(clean.begin(), clean.end(), px.begin());
        state.ResumeTiming();
        const std::int64_t a0 = bench::allocations();
        const auto t0 = std::chrono::steady_clock::now();
        if (!anchored_frame()) {
            state.SkipWithError(renderer->error().c_str());
            return;
        }
        const auto t1 = std::chrono::steady_clock::now();
        allocs += bench::allocations() - a0;
        ++frames;
        ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    std::int64_t area = 0;
    for (std::size_t i = 0; i < drawn.count; ++i)
        area += std::int64_t(drawn.rects[i].width) * drawn.rects[i].height;
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["allocs_per_frame"] = double(allocs) / double(frames);
    state.counters["rect_mpix"] = double(area) / 1e6;
}
BENCHMARK(BM_AnchoredOverlay1080p)
    ->Arg(0)
    ->Arg(1)
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3);

}  // namespace

BENCHMARK_MAIN();
