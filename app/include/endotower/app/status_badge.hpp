// StatusBadge: the appliance's corner badge, the spine's analysis stage.
//
// Inputs: the frame (any hal pixel format) and the handle's control events.
// Outputs: overlay, a small badge in the top-left corner (over the dark surround of
// the scope's circular field of view) showing the light level in the book's bands
// (ch. 4: 0-30 % red: tracking degrades; 30-45 % amber; 46-100 % green) and the
// handle's button and wheel activity; trace member
//   "status": {"light": 0..1, "clipped": 0..1, "band": "0-30"|"30-45"|"46-100",
//              "button_down": bool, "wheel": total detents}
// Parameters: sample_step (every 4th pixel in x and y).
// Glyphs are rendered once in configure(); process() allocates nothing.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "endotower/app/analysis_stage.hpp"

namespace endotower::app {

class StatusBadge final : public AnalysisStage {
public:
    explicit StatusBadge(int sample_step = 4) : step_(sample_step) {}

    std::string_view name() const override { return "status_badge"; }
    void configure(const hal::FrameFormat& format) override;
    void process(AnalysisContext& ctx) override;

    // Over the sample grid, the pixels brighter than the scope's dark surround
    // (luma > kSurround): their mean luma in 0..1 and the fraction at >= 250.
    // Measured inside the lit field of view so the black corners do not count as
    // low light. Both 0 for a black frame.
    static constexpr int kSurround = 10;
    static void measure(const hal::Frame& frame, int step, double& light, double& clipped);

private:
    void draw_text(OverlayCanvas& canvas, int x, int y, const char* text) const;
    int text_width(const char* text) const;

    int step_;
    int scale_ = 1;  // glyph cell size multiplier for the frame height
    int cell_w_ = 0, cell_h_ = 0;
    std::vector<std::uint8_t> glyphs_;  // per printable char: cell_w * cell_h alpha
    std::array<int, 96> advance_{};     // per printable char: pen advance in px
    bool button_down_ = false;
    std::int64_t wheel_total_ = 0;
};

}  // namespace endotower::app
