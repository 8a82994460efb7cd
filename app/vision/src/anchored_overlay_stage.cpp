#include "endotower/vision/anchored_overlay_stage.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

namespace endotower::vision {

namespace {

// The cube's faces: one warm tissue-contrasting colour, slightly translucent so the
// tissue under it stays visible at the edges.
constexpr hal::Rgba8 kCubeFace{90, 200, 255, 220};

}  // namespace

AnchoredOverlayStage::AnchoredOverlayStage(const RegionStage& regions,
                                           hal::OverlayRenderer* renderer, app::Log& log,
                                           double depth_mm)
    : regions_(regions), renderer_(renderer), log_(log), depth_mm_(depth_mm) {}

void AnchoredOverlayStage::set_image(int id, const hal::ImageView& image) {
    int slot = 0;
    for (const Image& i : images_) slot = std::max(slot, i.slot + 1);
    if (slot >= hal::OverlayRenderer::kMaxImages) {
        set_image_problem(id, "image not loaded: the renderer holds 8");
        return;
    }
    images_.push_back({id, slot, image, {}});
}

void AnchoredOverlayStage::set_image_problem(int id, std::string problem) {
    images_.push_back({id, -1, {}, std::move(problem)});
}

const AnchoredOverlayStage::Image* AnchoredOverlayStage::image_of(int id) const {
    const Image* fallback = nullptr;  // id -1: the board's, for regions outlined with the tool
    for (const Image& i : images_) {
        if (i.id == id) return &i;
        if (i.id == -1) fallback = &i;
    }
    return fallback;
}

void AnchoredOverlayStage::configure(const hal::FrameFormat& format) {
    width_ = format.width, height_ = format.height;
    renderer_configured_ = false;  // on the analysis thread, the first frame of this format
}

// A message where the overlay would be: a dark panel with the text, at the region's
// current centre (the polygon's vertices' mean).
void AnchoredOverlayStage::message(const RegionEstimate& e, std::string_view text) {
    double cx = 0, cy = 0;
    for (std::size_t i = 0; i < e.vertices; ++i)
        cx += e.polygon[i].x / static_cast<double>(e.vertices),
            cy += e.polygon[i].y / static_cast<double>(e.vertices);
    const float size = std::max(12.f, static_cast<float>(height_) / 36.f);
    hal::SceneText t;
    const std::size_t n = std::min(text.size(), t.utf8.size() - 1);
    std::memcpy(t.utf8.data(), text.data(), n);
    t.utf8[n] = '\0';
    t.x = static_cast<float>(cx) + 0.5f, t.y = static_cast<float>(cy) + 0.5f;
    t.size_px = size, t.align = hal::SceneText::Align::kCentre;
    t.colour = {255, 230, 120, 255};
    const float w = 0.55f * size * static_cast<float>(n) + size;
    scene_.quads.add(
        {t.x - w / 2, t.y - size * 0.8f, w, size * 1.6f, size * 0.3f, 0, {0, 0, 0, 170}, {}});
    scene_.texts.add(t);
}

bool AnchoredOverlayStage::target_mm(Vec3& out) const {
    if (!has_target_) return false;
    out = target_;
    return true;
}

void AnchoredOverlayStage::process(app::AnalysisContext& ctx) {
    scene_.clear();
    has_target_ = false;
    const std::span<const RegionEstimate> estimates = regions_.estimates();
    if (estimates.empty()) return;
    int target_id = 0;
    ctx.trace.begin_array("anchored");
    for (const RegionEstimate& e : estimates) {
        const bool tracked = e.state == RegionState::kTracked;
        TissuePose pose;
        // The SCI's target: the lowest-id tracked region's centre on the tissue.
        if (tracked && tissue_pose(e, scene_.camera, depth_mm_, pose) &&
            (!has_target_ || e.id < target_id)) {
            has_target_ = true, target_id = e.id, target_ = pose.origin_mm;
        }
        const RegionOverlayKind kind = regions_.overlay(e.id).kind;
        if (kind == RegionOverlayKind::kMarkers) continue;
        ctx.trace.begin_object().field("id", e.id).field("kind", to_string(kind));
        bool shown = false;
        if (kind == RegionOverlayKind::kImage) {
            const Image* im = image_of(e.id);
            std::array<Point2, 4> corners{};
            if (im == nullptr || im->slot < 0) {
                if (tracked)
                    message(e, im ? std::string_view(im->problem)
                                  : std::string_view("image not loaded"));
            } else if (tracked &&
                       anchored_image_corners(e, im->view.width, im->view.height, corners)) {
                hal::SceneImage s;
                s.image_id = im->slot;
                s.warped = true;
                for (std::size_t k = 0; k < 4; ++k)  // pixel centres -> pixel edges
                    s.corners[k] = {static_cast<float>(corners[k].x + 0.5),
                                    static_cast<float>(corners[k].y + 0.5)};
                shown = scene_.images.add(s);
            }
            ctx.trace.field("shown", shown);
            if (shown) {
                ctx.trace.begin_array("corners_px");
                for (const Point2& c : corners)
                    ctx.trace.begin_array().value(c.x).value(c.y).end_array();
                ctx.trace.end_array();
            }
        } else {
            if (tracked && !scene_.camera.valid())
                message(e, "3-D object: no calibrated camera (board: calibration)");
            else if (tracked && pose.valid) {
                std::array<hal::Rgba8, 6> faces;
                faces.fill(kCubeFace);
                shown = scene_.boxes.add(anchored_cube(pose, faces));
            }
            ctx.trace.field("shown", shown);
            if (shown)
                ctx.trace.begin_array("origin_mm")
                    .value(pose.origin_mm.x)
                    .value(pose.origin_mm.y)
                    .value(pose.origin_mm.z)
                    .end_array();
        }
        ctx.trace.end_object();
    }
    ctx.trace.end_array();

    if (renderer_ == nullptr || ctx.overlay.width() == 0) return;
    if (!renderer_configured_) {
        renderer_configured_ = true;
        if (!renderer_->configure(width_, height_)) {
            log_.printf(app::LogLevel::kWarning,
                        "regions: the overlay renderer cannot draw %dx%d: %s; anchored images "
                        "and objects are not drawn",
                        width_, height_, renderer_->error().c_str());
            renderer_ = nullptr;
            return;
        }
        for (const Image& i : images_)
            if (i.slot >= 0 && !renderer_->set_image(i.slot, i.view))
                log_.printf(app::LogLevel::kWarning, "regions: region %d's image: %s", i.id,
                            renderer_->error().c_str());
    }
    if (scene_.empty()) return;
    drawn_.count = 0;
    if (!renderer_->render(scene_, ctx.overlay.layer(), drawn_)) {
        if (!said_render_error_)
            log_.printf(app::LogLevel::kWarning, "regions: anchored overlay render failed: %s",
                        renderer_->error().c_str());
        said_render_error_ = true;
        return;
    }
    said_render_error_ = false;
    for (std::size_t i = 0; i < drawn_.count; ++i) ctx.overlay.mark(drawn_.rects[i]);
}

}  // namespace endotower::vision
