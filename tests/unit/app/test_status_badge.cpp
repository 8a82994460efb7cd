#include <gtest/gtest.h>

#include <vector>

#include "endotower/app/status_badge.hpp"

namespace endotower::app {
namespace {

hal::Frame bgr_frame(std::vector<std::uint8_t>& buf, int w, int h) {
    buf.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3, 0);
    hal::Frame f;
    f.format = {w, h, w * 3, hal::PixelFormat::kBgr24};
    f.data = buf.data();
    return f;
}

TEST(StatusBadge, MeasuresLumaAndClippedFraction) {
    std::vector<std::uint8_t> buf;
    hal::Frame f = bgr_frame(buf, 8, 8);
    // Left half white (luma 255, clipped), right half mid grey 100.
    for (std::size_t y = 0; y < 8; ++y)
        for (std::size_t x = 0; x < 8; ++x)
            for (std::size_t c = 0; c < 3; ++c) buf[(y * 8 + x) * 3 + c] = x < 4 ? 255 : 100;
    double light = 0, clipped = 0;
    StatusBadge::measure(f, 1, light, clipped);
    // (29+150+77) = 256 weights: white -> (255*256)>>8 = 255, grey -> 100.
    EXPECT_DOUBLE_EQ(light, (255.0 + 100.0) / 2.0 / 255.0);
    EXPECT_DOUBLE_EQ(clipped, 0.5);
}

TEST(StatusBadge, DrawsOnlyInTheTopLeftCornerAndTraces) {
    std::vector<std::uint8_t> buf;
    hal::Frame f = bgr_frame(buf, 1920, 1080);
    StatusBadge badge;
    badge.configure(f.format);
    OverlayCanvas canvas;
    canvas.configure(1920, 1080);
    JsonLine trace;
    trace.clear();
    trace.begin_object();
    const hal::ControlEvent press{hal::ControlEvent::Kind::kButtonPress, 0, 0, 1};
    AnalysisContext ctx{f, std::span<const hal::ControlEvent>(&press, 1), canvas, trace, 0};
    badge.process(ctx);
    trace.end_object();
    EXPECT_EQ(trace.view(),
              R"({"status":{"light":0,"clipped":0,"band":"0-30","button_down":true,"wheel":0}})");
    ASSERT_GE(canvas.layer().rect_count, 1u);
    for (std::size_t i = 0; i < canvas.layer().rect_count; ++i) {
        const hal::Rect& r = canvas.layer().rects[i];
        EXPECT_LE(r.x + r.width, 1920 / 4);
        EXPECT_LE(r.y + r.height, 1080 / 8);
    }
    // Clearing leaves a fully transparent layer.
    canvas.clear();
    for (int y = 0; y < 1080; y += 7)
        for (int x = 0; x < 1920; x += 5) ASSERT_EQ(canvas.row(y)[4 * x + 3], 0);
}

}  // namespace
}  // namespace endotower::app
