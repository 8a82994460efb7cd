// SciStage with a recording fake renderer: the renderer is configured and given the
// media images on the analysis thread's first frame (not in configure()), renders only
// a non-empty scene, its drawn rectangles are marked on the canvas; without a renderer
// the stage runs, traces, and says so once.
#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

#include "endotower/sci/sci_stage.hpp"

namespace endotower::sci {
namespace {

class FakeRenderer final : public hal::OverlayRenderer {
public:
    std::string_view name() const override { return "fake"; }
    bool configure(int w, int h) override {
        configured.push_back({w, h});
        configure_thread = std::this_thread::get_id();
        return true;
    }
    bool set_image(int id, const hal::ImageView& v) override {
        images.push_back({id, v.width});
        return true;
    }
    bool render(const hal::OverlayScene& scene, const hal::OverlayLayer&,
                hal::DrawnRects& drawn) override {
        ++renders;
        quads = scene.quads.count;
        drawn.rects[0] = {10, 20, 30, 40};
        drawn.count = 1;
        return true;
    }
    const std::string& error() const override { return error_; }

    std::vector<std::pair<int, int>> configured, images;
    std::thread::id configure_thread;
    int renders = 0;
    std::size_t quads = 0;
    std::string error_;
};

class FakeLog final : public app::Log {
public:
    void write(app::LogLevel, std::string_view m) override { lines.emplace_back(m); }
    std::vector<std::string> lines;
};

struct Harness {
    hal::FrameFormat format{640, 480, 640 * 3, hal::PixelFormat::kBgr24};
    std::vector<std::uint8_t> pixels = std::vector<std::uint8_t>(640 * 480 * 3);
    app::OverlayCanvas canvas;
    app::JsonLine trace;
    Harness() { canvas.configure(640, 480); }
    void run(SciStage& s, hal::Nanos t, std::vector<hal::ControlEvent> events = {}) {
        hal::Frame f;
        f.format = format;
        f.data = pixels.data();
        f.capture_ns = t;
        canvas.clear();
        trace.clear();
        trace.begin_object();
        app::AnalysisContext ctx{f, events, canvas, trace, 0};
        s.process(ctx);
        trace.end_object();
    }
};

TEST(SciStage, ConfiguresTheRendererOnTheAnalysisThreadAndMarksWhatItDrew) {
    FakeRenderer r;
    FakeLog log;
    SciMedia media;
    media.names[0] = {"a.png", "b.png"};
    media.slots[0] = {0, 1};
    const std::vector<std::uint8_t> px(4 * 2 * 2);
    media.uploads = {{2, 2, 8, px.data()}, {2, 2, 8, px.data()}};
    SciStage stage(SciParams{}, nullptr, nullptr, &r, log, media);
    Harness h;
    stage.configure(h.format);
    EXPECT_TRUE(r.configured.empty());  // not on the configuring (video) thread
    std::thread analysis([&] {
        h.run(stage, 0);
        EXPECT_EQ(r.configure_thread, std::this_thread::get_id());
    });
    analysis.join();
    ASSERT_EQ(r.configured.size(), 1u);
    EXPECT_EQ(r.configured[0], (std::pair<int, int>{640, 480}));
    EXPECT_EQ(r.images, (std::vector<std::pair<int, int>>{{0, 2}, {1, 2}}));
    EXPECT_EQ(r.renders, 0);  // inactive: nothing to draw
    EXPECT_EQ(h.trace.view(),
              R"({"sci":{"state":"inactive","menu":null,"highlighted":null,"event":null}})");
    EXPECT_EQ(h.canvas.layer().rect_count, 0u);

    h.run(stage, 40'000'000, {{hal::ControlEvent::Kind::kButtonPress, 0, 0, 40'000'000}});
    EXPECT_EQ(r.renders, 1);
    EXPECT_EQ(r.quads, 4u);  // the three-level main menu
    ASSERT_EQ(h.canvas.layer().rect_count, 1u);
    EXPECT_EQ(h.canvas.layer().rects[0], (hal::Rect{10, 20, 30, 40}));
    EXPECT_EQ(
        h.trace.view(),
        R"({"sci":{"state":"menu","menu":"main","highlighted":null,"event":"activate_button"}})");
    EXPECT_EQ(r.configured.size(), 1u);
    EXPECT_TRUE(log.lines.empty());
}

TEST(SciStage, WithoutARendererItRunsTracesAndSaysSoOnce) {
    FakeLog log;
    SciStage stage(SciParams{}, nullptr, nullptr, nullptr, log);
    Harness h;
    stage.configure(h.format);
    for (int k = 0; k < 5; ++k) h.run(stage, k * 40'000'000);
    h.run(stage, 200'000'000, {{hal::ControlEvent::Kind::kButtonPress, 0, 0, 200'000'000}});
    EXPECT_EQ(
        h.trace.view(),
        R"({"sci":{"state":"menu","menu":"main","highlighted":null,"event":"activate_button"}})");
    EXPECT_EQ(stage.scene().quads.count, 4u);
    EXPECT_EQ(h.canvas.layer().rect_count, 0u);
    stage.configure(h.format);  // a format change: still said only once
    ASSERT_EQ(log.lines.size(), 1u);
    EXPECT_NE(log.lines[0].find("no overlay renderer"), std::string::npos);
}

}  // namespace
}  // namespace endotower::sci
