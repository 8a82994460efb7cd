// AnalysisChain: the analysis path the board file describes, built the same way for
// `endotower sim` and `endotower run`: the calibration check (first: with
// analysis.fov_mask it blackens the analysis frame outside the field of view), the
// status badge, the tool tracker (with the 3-D pose when the board's calibration
// matches the input size), the strip markers, the gestures, the regions (marked from
// the command line, the timeline, or with the tool tip: analysis.regions.mark_with_tool)
// then the images and cubes anchored to them (AnchoredOverlayStage, with a GLES
// renderer of its own; analysis.regions.overlay or each mark's overlay), and the
// surgeon-computer interface (board `sci:`; its image box target rides on the first
// tracked region), in that order in one app::StageChain.
//
// build(): `input` is the size the analysis will see (for the calibration match);
// `marks` are the regions to track (may be empty); `renderer` draws the SCI's overlay
// (borrowed; null: the SCI runs and traces without drawing); `log` is borrowed for the
// chain's lifetime; `command` prefixes the messages ("sim", "run"). False with `error`
// on bad input (a model or calibration file that cannot be read): exit 2. A gesture
// model that cannot be loaded, or SCI media that are missing, only disable that part
// (stderr says so). The chain owns its stages; stage() is null when it is empty.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "board_config.hpp"
#include "endotower/app/analysis_stage.hpp"
#include "endotower/app/log.hpp"
#include "endotower/hal/frame.hpp"
#include "endotower/hal/overlay_renderer.hpp"
#include "endotower/vision/region_stage.hpp"

namespace endotower::media {
struct MediaImage;
}

namespace endotower::firmware {

class AnalysisChain {
public:
    AnalysisChain();
    ~AnalysisChain();
    bool build(const BoardConfig& board, const hal::FrameFormat& input,
               std::vector<vision::RegionMark> marks, hal::OverlayRenderer* renderer, app::Log& log,
               const char* command, std::string& error);
    app::AnalysisStage* stage();
    // The region stage (its errors() after the run); valid after build().
    const vision::RegionStage& regions() const;

    using AnchorImages = std::vector<std::unique_ptr<media::MediaImage>>;

private:
    struct Parts;
    std::unique_ptr<Parts> parts_;
};

}  // namespace endotower::firmware
