// SciStage: the surgeon-computer interface on the analysis path. Runs after the tool
// tracker and the gesture stage in the StageChain and reads their results for this
// frame: tools[0]'s tip is the cursor (with its 3-D pose when calibrated), the frame's
// gesture drives activation, selection and the quadrant menu; handle events come in
// ctx.events. One SciMachine step per frame, then the OverlayScene is built and, with
// a renderer, drawn over the canvas.
//
// Borrows `tracking`, `gestures` (either may be null: no cursor / no gestures) and
// `renderer` (null: the SCI still runs and traces; the log says once that the overlay
// is not drawn), all for the stage's lifetime; `log` likewise. `media` is moved in.
// The renderer is configured (and the media images registered) on the first frame
// after configure(), on the analysis thread that renders: one GL context, one thread.
// Trace member, every frame:
//   "sci": {"state": string, "menu": string|null, "highlighted": string|null,
//           "event": string|null}   (menu null while inactive; docs/sci.md)
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/app/log.hpp"
#include "endotower/hal/overlay_renderer.hpp"
#include "endotower/sci/sci_machine.hpp"
#include "endotower/sci/sci_scene.hpp"

namespace endotower::vision {
class ToolTrackingStage;
class GestureStage;
class AnchoredOverlayStage;
}  // namespace endotower::vision

namespace endotower::sci {

// The patient data the functions show: image names per modality (ct, xray, mri) and
// the renderer slot of each (-1: not loaded, `message` says why); `uploads[i]` is
// registered as slot i when the stage is configured (borrowed pixels: they must
// outlive the stage).
struct SciMedia {
    std::array<std::vector<std::string>, kModalityCount> names;
    std::array<std::vector<int>, kModalityCount> slots;
    std::vector<hal::ImageView> uploads;
    std::vector<std::string> record_lines;
    std::string message;
};

class SciStage final : public app::AnalysisStage {
public:
    SciStage(SciParams params, const vision::ToolTrackingStage* tracking,
             const vision::GestureStage* gestures, hal::OverlayRenderer* renderer, app::Log& log,
             SciMedia media = {});
    std::string_view name() const override { return "sci"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;
    // The calibrated pinhole of the input image (the image box, the 3-D thread).
    void set_camera(const hal::SceneCamera& camera) { scene_.camera = camera; }
    // The image box's target marker follows the tissue point of the first tracked
    // region of `anchored` (borrowed; it runs before this stage); while none is tracked
    // it stays where it was last (issue 8, fig. 4.41/4.42).
    void set_target_source(const vision::AnchoredOverlayStage* anchored) { anchored_ = anchored; }
    const SciMachine& machine() const { return machine_; }
    const hal::OverlayScene& scene() const { return scene_; }

private:
    void configure_renderer();
    SciParams params_;
    const vision::ToolTrackingStage* tracking_;
    const vision::GestureStage* gestures_;
    const vision::AnchoredOverlayStage* anchored_ = nullptr;
    hal::OverlayRenderer* renderer_;
    app::Log& log_;
    SciMedia media_;
    std::vector<std::string_view> record_view_;
    SciMachine machine_;
    hal::OverlayScene scene_;
    hal::DrawnRects drawn_;
    int width_ = 0, height_ = 0;
    bool said_no_renderer_ = false, said_render_error_ = false, renderer_configured_ = false;
};

}  // namespace endotower::sci
