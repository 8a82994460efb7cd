// TestPatternStage: the overlay `endotower selftest` shows on the monitor: colour
// bars along the bottom (the 75 % EBU bars: white, yellow, cyan, green, magenta, red,
// blue, black) and a banner with the check in progress and what the technician must
// do ("PRESS THE HANDLE BUTTON", ...), above the live video.
//
// Inputs: the frame's format (configure), the current prompt (set_prompt, any
// thread). Outputs: overlay only; trace member "selftest_prompt": index.
// Every prompt is rendered once in configure(); process() only copies pixels.
#pragma once

#include <atomic>
#include <string>
#include <vector>

#include "endotower/app/analysis_stage.hpp"

namespace endotower::app {

class TestPatternStage final : public AnalysisStage {
public:
    // The prompts, by index; set_prompt(i) selects one.
    explicit TestPatternStage(std::vector<std::string> prompts);

    std::string_view name() const override { return "test_pattern"; }
    void configure(const hal::FrameFormat& format) override;
    void process(AnalysisContext& ctx) override;

    void set_prompt(int index) { prompt_.store(index, std::memory_order_relaxed); }
    // The bars' colours, left to right (R G B), for tests.
    static constexpr Rgba kBars[8] = {{191, 191, 191, 255}, {191, 191, 0, 255}, {0, 191, 191, 255},
                                      {0, 191, 0, 255},     {191, 0, 191, 255}, {191, 0, 0, 255},
                                      {0, 0, 191, 255},     {0, 0, 0, 255}};
    // Where the bars and the banner go for a width x height frame.
    static hal::Rect bars_rect(int width, int height);
    static hal::Rect banner_rect(int width, int height);

private:
    std::vector<std::string> prompts_;
    std::atomic<int> prompt_{0};
    int width_ = 0, height_ = 0;
    std::vector<std::vector<std::uint8_t>> banners_;  // per prompt: banner_rect RGBA
};

}  // namespace endotower::app
