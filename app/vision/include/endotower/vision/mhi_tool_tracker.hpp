// MhiToolTracker: the book's motion history image tracker (ch. 4, fig. 4.1-4.6),
// tracker name `mhi`. On the grey frame reduced to `analysis_width` (320): the
// silhouette is where consecutive frames differ by more than `diff_threshold` (30);
// the motion history image keeps each pixel's last motion time and forgets it after
// `duration_frames` (8) (cv::motempl::updateMotionHistory); its gradient orientation
// (calcMotionGradient, calcGlobalOrientation) is the direction of motion. The moving
// region (the recent history, closed with a 7 px ellipse, inside the lit field of
// view) gives the bounding box, the axis by second moments and the tip at the end
// away from the rim; when neither end is nearer the rim, the end towards the motion.
// A tool that stops moving fades out of the history: "no tool" (the book's
// limitation). One tool; results in full-resolution coordinates.
#pragma once

#include <memory>

#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

struct MhiToolTrackerParams {
    int analysis_width = 320;
    int diff_threshold = 30;
    int duration_frames = 8;
};

class MhiToolTracker final : public ToolTracker {
public:
    explicit MhiToolTracker(MhiToolTrackerParams params = {});
    ~MhiToolTracker() override;
    std::string_view name() const override { return "mhi"; }
    void configure(const hal::FrameFormat& format) override;
    std::size_t track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) override;
    // The last frame's moving region's bounding box in full-resolution pixels
    // (x, y, width, height; all 0 when none): the particle tracker starts from it.
    void last_box(int box[4]) const;

private:
    struct Work;
    MhiToolTrackerParams params_;
    std::unique_ptr<Work> work_;
};

}  // namespace endotower::vision
