// AnchoredOverlayStage: draws the images and 3-D objects anchored to tracked regions
// (issue 7). Runs after RegionStage in the StageChain and reads its estimates of the
// same frame: a region whose overlay (RegionStage::overlay) is
//   image   gets its image fitted into the marked polygon's bounding box and moved by
//           the region's homography, drawn as a perspective-correct warped quad;
//   object  gets a cube standing on its tissue plane (tissue_pose: the plane at
//           `depth_mm` when marked, default 80 mm), drawn through the calibrated camera
//           (eq. 4.28-4.32, the SCI's image box camera);
// only while the region is tracked: hidden, not misplaced, when it is lost. An image
// that could not be loaded, or an object without a calibrated camera, shows a message
// at the region instead; the video goes on.
//
// Borrows `regions`, `renderer` (null: the scene is built and traced but not drawn)
// and `log` for the stage's lifetime. set_image() borrows the pixels likewise; they
// are registered with the renderer (slots in call order) on the first frame after
// configure(), on the analysis thread. No allocation per frame.
// Trace member, every frame with regions:
//   "anchored": [{"id", "kind": "image" | "object", "shown", "corners_px": [[x, y] x4]
//                 (image, shown), "origin_mm": [x, y, z] (object, shown)}]
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/app/log.hpp"
#include "endotower/hal/overlay_renderer.hpp"
#include "endotower/vision/region_stage.hpp"

namespace endotower::vision {

class AnchoredOverlayStage final : public app::AnalysisStage {
public:
    AnchoredOverlayStage(const RegionStage& regions, hal::OverlayRenderer* renderer, app::Log& log,
                         double depth_mm = 80);
    // Before the run: region `id`'s image, or why it has none (`problem`, shown at it);
    // id -1: for image regions without one of their own (those outlined with the tool).
    void set_image(int id, const hal::ImageView& image);
    void set_image_problem(int id, std::string problem);
    void set_camera(const hal::SceneCamera& camera) { scene_.camera = camera; }

    std::string_view name() const override { return "anchored"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;

    // This frame's draw list.
    const hal::OverlayScene& scene() const { return scene_; }
    // The tissue point at the centre of the lowest-id tracked region this frame, in
    // camera millimetres (the SCI's image box target); false when none or no camera.
    bool target_mm(Vec3& out) const;

private:
    struct Image {
        int id = 0, slot = -1;
        hal::ImageView view;
        std::string problem;
    };
    const Image* image_of(int id) const;
    void message(const RegionEstimate& e, std::string_view text);
    const RegionStage& regions_;
    hal::OverlayRenderer* renderer_;
    app::Log& log_;
    double depth_mm_;
    std::vector<Image> images_;
    hal::OverlayScene scene_;
    hal::DrawnRects drawn_;
    int width_ = 0, height_ = 0;
    bool renderer_configured_ = false, said_render_error_ = false;
    bool has_target_ = false;
    Vec3 target_;
};

}  // namespace endotower::vision
