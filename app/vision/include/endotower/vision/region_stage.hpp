// RegionStage: runs a RegionTracker on the analysis path, marks the regions it is
// given at their frames, draws the anchored overlay and writes the trace member
//   "regions": [{"id", "polygon_px": [[x, y], ...], "state": "tracked" | "lost",
//                "inliers"}]
// every frame once a region is marked (polygon_px: the last known outline while lost),
// in the input's own pixel coordinates. The overlay (the outline, its corners and a
// marker at its centre) is drawn only while the region is tracked: hidden, never
// misplaced, when it is lost. Borrows the tracker.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/vision/region_tracker.hpp"

namespace endotower::vision {

struct RegionMark {
    std::int64_t frame = 0;  // source sequence number (0 = the first frame)
    int id = 0;
    std::vector<Point2> polygon;  // in that frame's pixels
};

class RegionStage final : public app::AnalysisStage {
public:
    explicit RegionStage(RegionTracker& tracker) : tracker_(tracker) {}
    // Before the run: a region to mark at the first analysed frame >= mark.frame.
    void schedule(RegionMark mark);
    // After the run: marks that failed ("frame N: region 2: ..."), one per line.
    const std::vector<std::string>& errors() const { return errors_; }

    std::string_view name() const override { return "regions"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;

private:
    RegionTracker& tracker_;
    std::vector<RegionMark> pending_;  // sorted by frame
    std::size_t next_ = 0;
    std::vector<std::string> errors_;
    std::array<RegionEstimate, RegionTracker::kMaxRegions> estimates_{};
    int thickness_ = 2;
};

}  // namespace endotower::vision
