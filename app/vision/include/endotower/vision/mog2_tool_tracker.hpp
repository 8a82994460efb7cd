// Mog2ToolTracker: the book's adaptive Gaussian mixture background model (ch. 4,
// "Adaptive Gaussian Mixture Model", fig. 4.17-4.18, appendix III), tracker name
// `mog2`. OpenCV's BackgroundSubtractorMOG2 is the same model (Zivkovic's adaptive
// mixture, per-pixel component count): on the frame reduced to `analysis_width`
// (320), with `history` (200) frames and `var_threshold` (16); shadows are detected
// (value 127) and eliminated (only 255 is foreground), then a 3x3 opening and a
// `close_px` (7) closing; the foreground inside the lit field of view is the tool
// region. From it (RegionDescriber): the axis by second moments, the incision at the
// end nearer the rim, the tip at the far end, the head, the edges; results in
// full-resolution coordinates. A region smaller than 0.2 % of the picture or less
// than twice as long as wide is "no tool". The model needs motion: a tool held still
// for about `history` frames becomes background (the book's limitation). One tool.
#pragma once

#include <memory>

#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

struct Mog2ToolTrackerParams {
    int analysis_width = 320;
    int history = 200;
    double var_threshold = 16;
    int close_px = 7;
};

class Mog2ToolTracker final : public ToolTracker {
public:
    explicit Mog2ToolTracker(Mog2ToolTrackerParams params = {});
    ~Mog2ToolTracker() override;
    std::string_view name() const override { return "mog2"; }
    void configure(const hal::FrameFormat& format) override;
    std::size_t track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) override;
    // The last frame's tool region's bounding box in full-resolution pixels (x, y,
    // width, height; all 0 when no tool): the hybrid tracker starts from it.
    void last_box(int box[4]) const;

private:
    struct Work;
    Mog2ToolTrackerParams params_;
    std::unique_ptr<Work> work_;
};

}  // namespace endotower::vision
