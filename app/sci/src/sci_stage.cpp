#include "endotower/sci/sci_stage.hpp"

#include <utility>

#include "endotower/vision/anchored_overlay_stage.hpp"
#include "endotower/vision/gesture_classifier.hpp"
#include "endotower/vision/gesture_stage.hpp"
#include "endotower/vision/tool_tracking_stage.hpp"

namespace endotower::sci {

namespace {

SciGesture to_sci_gesture(int label) {
    if (label < 0) return SciGesture::kNone;
    const std::string_view l = vision::kGestureLabels[static_cast<std::size_t>(label)];
    if (l == "open_grasper") return SciGesture::kOpenGrasper;
    if (l == "open_scissors" || l == "closed_scissors") return SciGesture::kScissors;
    if (l == "cross") return SciGesture::kCross;
    if (l == "triangle" || l == "double_triangle") return SciGesture::kOpenCrossing;
    return SciGesture::kOther;
}

}  // namespace

SciStage::SciStage(SciParams params, const vision::ToolTrackingStage* tracking,
                   const vision::GestureStage* gestures, hal::OverlayRenderer* renderer,
                   app::Log& log, SciMedia media)
    : params_(params),
      tracking_(tracking),
      gestures_(gestures),
      renderer_(renderer),
      log_(log),
      media_(std::move(media)) {
    for (std::size_t m = 0; m < kModalityCount; ++m) {
        params_.image_counts[m] = static_cast<int>(media_.names[m].size());
        media_.slots[m].resize(media_.names[m].size(), -1);
    }
    for (const std::string& l : media_.record_lines) record_view_.push_back(l);
    machine_ = SciMachine(params_);
}

void SciStage::configure(const hal::FrameFormat& format) {
    width_ = format.width, height_ = format.height;
    machine_.configure(width_, height_);
    machine_.set_camera(scene_.camera);
    // The renderer is configured on the analysis thread, where it renders (its GL
    // context is current on one thread): on the first frame of this format.
    renderer_configured_ = false;
    if (renderer_ == nullptr && !said_no_renderer_) {
        log_.printf(app::LogLevel::kInfo,
                    "sci: no overlay renderer; the SCI runs and traces, its overlay is not drawn");
        said_no_renderer_ = true;
    }
}

void SciStage::configure_renderer() {
    renderer_configured_ = true;
    if (!renderer_->configure(width_, height_)) {
        log_.printf(app::LogLevel::kWarning,
                    "sci: the overlay renderer %.*s cannot draw %dx%d: %s; the SCI runs without "
                    "its overlay",
                    static_cast<int>(renderer_->name().size()), renderer_->name().data(), width_,
                    height_, renderer_->error().c_str());
        renderer_ = nullptr;
        return;
    }
    for (std::size_t i = 0; i < media_.uploads.size(); ++i)
        if (!renderer_->set_image(static_cast<int>(i), media_.uploads[i]))
            log_.printf(app::LogLevel::kWarning,
                        "sci: image %zu not registered with the renderer: %s", i,
                        renderer_->error().c_str());
}

void SciStage::process(app::AnalysisContext& ctx) {
    SciFrame f;
    f.t_ns = ctx.frame.capture_ns;
    f.events = ctx.events;
    std::array<double, 2> confidence{};
    if (tracking_ != nullptr) {
        for (std::size_t i = 0; i < tracking_->tool_count() && f.tool_count < 2; ++i) {
            const vision::ToolEstimate& t = tracking_->tool(i);
            if (!t.present && t.confidence <= 0) continue;
            confidence[static_cast<std::size_t>(f.tool_count)] = t.confidence;
            SciTool& s = f.tools[static_cast<std::size_t>(f.tool_count++)];
            s.x = t.tip.x, s.y = t.tip.y;
            const vision::ToolPose& p = tracking_->pose(i);
            s.has_3d = p.valid;
            s.tip_mm = {p.tip_mm.x, p.tip_mm.y, p.tip_mm.z};
            s.axis_dir = {p.axis_dir.x, p.axis_dir.y, p.axis_dir.z};
        }
    }
    if (gestures_ != nullptr) {
        const vision::GestureFrame& g = gestures_->current();
        f.gesture = to_sci_gesture(g.label);
        f.gesture_held_ms = g.held_ms;
        f.gesture_fired = g.fired;
        f.gesture_x = g.tip.x, f.gesture_y = g.tip.y;
        f.tools_touching = g.touching;
        f.gesture_dropout = g.dropout;
    }
    // The cursor is the surest tool.
    if (f.tool_count == 2 && confidence[1] > confidence[0]) std::swap(f.tools[0], f.tools[1]);
    vision::Vec3 target;
    if (anchored_ != nullptr && anchored_->target_mm(target))
        machine_.set_box_target({target.x, target.y, target.z});
    machine_.step(f);

    const SciMachine& m = machine_;
    ctx.trace.begin_object("sci").field("state", to_string(m.state()));
    if (m.active())
        ctx.trace.field("menu", to_string(m.menu().id));
    else
        ctx.trace.null_field("menu");
    if (m.active() && m.highlighted() >= 0)
        ctx.trace.field("highlighted",
                        m.menu().items[static_cast<std::size_t>(m.highlighted())].label);
    else
        ctx.trace.null_field("highlighted");
    if (!m.event().empty())
        ctx.trace.field("event", m.event());
    else
        ctx.trace.null_field("event");
    ctx.trace.end_object();

    SciSceneInput in;
    in.width = width_, in.height = height_;
    in.has_tip = f.tool_count > 0;
    in.tip_x = static_cast<float>(f.tools[0].x), in.tip_y = static_cast<float>(f.tools[0].y);
    in.gesture_x = static_cast<float>(f.gesture_x), in.gesture_y = static_cast<float>(f.gesture_y);
    const auto mod = static_cast<std::size_t>(m.modality());
    if (m.image_index() < static_cast<int>(media_.names[mod].size())) {
        const auto k = static_cast<std::size_t>(m.image_index());
        in.image_name = media_.names[mod][k];
        in.image_slot = media_.slots[mod][k];
    }
    in.image_message = media_.message.empty() ? std::string_view("image not loaded")
                                              : std::string_view(media_.message);
    in.record_lines = record_view_;
    in.suture_in_mm =
        f.tool_count >= 2 && f.tools[0].has_3d && f.tools[1].has_3d && scene_.camera.valid();
    build_sci_scene(m, params_, in, scene_);

    if (renderer_ != nullptr && !renderer_configured_) configure_renderer();
    if (renderer_ == nullptr || scene_.empty()) return;
    drawn_.count = 0;
    if (!renderer_->render(scene_, ctx.overlay.layer(), drawn_)) {
        if (!said_render_error_)
            log_.printf(app::LogLevel::kWarning, "sci: overlay render failed: %s",
                        renderer_->error().c_str());
        said_render_error_ = true;
        return;
    }
    said_render_error_ = false;
    for (std::size_t i = 0; i < drawn_.count; ++i) ctx.overlay.mark(drawn_.rects[i]);
}

}  // namespace endotower::sci
