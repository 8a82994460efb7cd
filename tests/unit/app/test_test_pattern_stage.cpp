// TestPatternStage: the colour bars and the prompt banner, exact where it matters.
#include <gtest/gtest.h>

#include "endotower/app/test_pattern_stage.hpp"

namespace endotower::app {
namespace {

TEST(TestPatternStage, BarsAndThePromptOfTheMoment) {
    TestPatternStage stage({"WAIT", "PRESS THE HANDLE BUTTON"});
    const hal::FrameFormat f{640, 360, 640 * 3, hal::PixelFormat::kBgr24};
    stage.configure(f);
    OverlayCanvas canvas;
    canvas.configure(640, 360);
    std::vector<std::uint8_t> px(f.size_bytes());
    hal::Frame frame{f, px.data()};
    JsonLine trace;
    trace.begin_object();
    AnalysisContext ctx{frame, {}, canvas, trace, 0};
    stage.set_prompt(1);
    stage.process(ctx);
    const hal::Rect bars = TestPatternStage::bars_rect(640, 360);
    for (int i = 0; i < 8; ++i) {
        const int x = 640 * i / 8 + 40, y = bars.y + bars.height / 2;
        const std::uint8_t* p = canvas.row(y) + 4 * x;
        EXPECT_EQ(p[0], TestPatternStage::kBars[i].r) << i;
        EXPECT_EQ(p[1], TestPatternStage::kBars[i].g) << i;
        EXPECT_EQ(p[2], TestPatternStage::kBars[i].b) << i;
        EXPECT_EQ(p[3], 255) << i;
    }
    // The banner: translucent dark box with opaque white text somewhere inside.
    const hal::Rect b = TestPatternStage::banner_rect(640, 360);
    EXPECT_EQ(canvas.row(b.y + 1)[4 * (b.x + 1) + 3], 200);
    int white = 0;
    for (int y = b.y; y < b.y + b.height; ++y)
        for (int x = b.x; x < b.x + b.width; ++x)
            white += canvas.row(y)[4 * x] > 200 && canvas.row(y)[4 * x + 1] > 200 &&
                     canvas.row(y)[4 * x + 2] > 200;
    EXPECT_GT(white, 100);
    // Nothing between the banner and the bars.
    EXPECT_EQ(canvas.row(b.y + b.height + 5)[4 * 320 + 3], 0);
    EXPECT_EQ(canvas.layer().rect_count, 9u);
}

TEST(TestPatternStage, PromptsDiffer) {
    TestPatternStage stage({"ONE", "TWO TWO TWO"});
    const hal::FrameFormat f{320, 180, 320 * 3, hal::PixelFormat::kBgr24};
    stage.configure(f);
    std::vector<std::uint8_t> px(f.size_bytes());
    hal::Frame frame{f, px.data()};
    auto draw = [&](int prompt) {
        OverlayCanvas canvas;
        canvas.configure(320, 180);
        JsonLine trace;
        trace.begin_object();
        AnalysisContext ctx{frame, {}, canvas, trace, 0};
        stage.set_prompt(prompt);
        stage.process(ctx);
        const hal::Rect b = TestPatternStage::banner_rect(320, 180);
        std::vector<std::uint8_t> out;
        for (int y = b.y; y < b.y + b.height; ++y)
            out.insert(out.end(), canvas.row(y) + 4 * b.x, canvas.row(y) + 4 * (b.x + b.width));
        return out;
    };
    EXPECT_NE(draw(0), draw(1));
    EXPECT_EQ(draw(1), draw(1));
}

}  // namespace
}  // namespace endotower::app
