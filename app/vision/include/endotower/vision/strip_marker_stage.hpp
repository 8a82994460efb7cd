// StripMarkerStage: strip-marker tracking (book ch. 3, StripMarkerTracker) on the
// analysis path. Writes the trace member, every frame,
//   "markers": [{"center_px": [x, y], "corners_px": [[x, y] x 4], "diameter_px",
//                "strips", "depth_mm": z or null, "tip_mm": [x, y, z] or null}]
// one object per tool with a marker (at most two): E, the trapezoid ABCD of the
// visible strip nearest the tip and its apparent diameter M (input pixels), how many
// strips that tool shows, and with a calibration (the tracker's set_calibration) the
// depth from M and "tip_mm", E in the camera frame in mm (eq. 3.1/3.2): the book's
// marker-based tool position ("Tool Center", fig. 3.8). Overlay: a cross at E.
// Borrows the tracker.
#pragma once

#include <array>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/vision/strip_marker_tracker.hpp"

namespace endotower::vision {

class StripMarkerStage final : public app::AnalysisStage {
public:
    explicit StripMarkerStage(StripMarkerTracker& tracker) : tracker_(tracker) {}
    std::string_view name() const override { return "strip_markers"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;

private:
    StripMarkerTracker& tracker_;
    std::array<StripMarker, StripMarkerTracker::kMaxMarkers> markers_{};
    int arm_ = 8;
};

}  // namespace endotower::vision
