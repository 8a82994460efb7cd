// AnalysisStage: work that runs beside the video path on the newest frame (tracking,
// gestures, regions, the surgeon-computer interface) and draws the overlay.
//
// Contract:
//  inputs   a pipeline-owned copy of the frame (the stage never holds a capture
//           buffer), and the handle's control events since the previous call;
//  outputs  the overlay (canvas cleared before the call) and the stage's members of
//           the frame's trace line;
//  timing   runs on the analysis thread; a result not ready by the frame's compose
//           time is used by a later frame (the trace says how old), never waited
//           for. It may throw (std::exception, std::bad_alloc) or hang: the pipeline
//           then shows raw video and recovers when the stage does.
#pragma once

#include <span>
#include <string_view>

#include "endotower/app/json_line.hpp"
#include "endotower/app/overlay_canvas.hpp"
#include "endotower/hal/control_input.hpp"
#include "endotower/hal/frame.hpp"

namespace endotower::app {

struct AnalysisContext {
    const hal::Frame& frame;
    std::span<const hal::ControlEvent> events;
    OverlayCanvas& overlay;
    JsonLine& trace;  // append members with field()/begin_object(key)
    // Virtual time this call costs in deterministic replay; preset to the
    // pipeline's configured cost, a stage may raise it (to model real overruns).
    hal::Nanos virtual_cost_ns;
};

class AnalysisStage {
public:
    virtual ~AnalysisStage() = default;
    virtual std::string_view name() const = 0;
    // Called off the per-frame path for every new format: allocate here.
    virtual void configure(const hal::FrameFormat& format) = 0;
    virtual void process(AnalysisContext& ctx) = 0;
};

}  // namespace endotower::app
