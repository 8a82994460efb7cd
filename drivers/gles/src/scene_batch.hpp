// SceneBatch: turns a hal::OverlayScene into vertex arrays for the renderer's GL
// programs and the screen rectangles they cover, on the CPU. Capacities follow the
// scene's lists, so after reserve() build() never allocates.
//
// Shapes (quads, sectors, discs, 2-D and projected 3-D line segments) are one quad
// per item over its bounding box; the fragment shader computes the coverage from a
// signed distance (see gles_renderer.cpp). Pixel coordinates are edges: pixel (i, j)
// spans [i, i+1) x [j, j+1). The pinhole's u, v (pixel centres at integers) become
// edges by + 0.5.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "endotower/hal/overlay_renderer.hpp"
#include "glyph_atlas.hpp"

namespace endotower::gles {

struct ShapeVertex {
    float x, y;    // pixels
    float lx, ly;  // relative to the shape's origin
    float shape[4], shape2[4];
    float fill[4], border[4];  // straight alpha, 0..1
};
struct TexVertex {
    float x, y, u, v;
    float colour[4];
};
struct BoxVertex {
    float x, y, z;  // camera millimetres
    float nx, ny, nz;
    float colour[4];
};

// Rectangles that overlap are merged (so no pixel is composited twice); past
// `kMaxOut` the pair whose union grows least is merged.
class RectSet {
public:
    static constexpr std::size_t kCapacity = 256;
    void clear() { count_ = 0; }
    void add(const hal::Rect& r);  // clipped by the caller
    void finish(hal::DrawnRects& out);

private:
    void merge_into(std::size_t keep, std::size_t drop);
    std::array<hal::Rect, kCapacity> rects_{};
    std::size_t count_ = 0;
};

// clip_from_camera for the pinhole (eq. 4.28-4.32), column-major, for a
// width x height target whose GL row 0 is image row 0.
std::array<float, 16> clip_from_camera(const hal::SceneCamera& camera, int width, int height);

struct SceneBatch {
    std::vector<ShapeVertex> shapes;
    std::size_t shapes_used = 0, lines3_end = 0;  // [0, lines3_end) are the 3-D lines
    std::vector<TexVertex> text, images;
    std::size_t text_used = 0, images_used = 0;  // images: 6 vertices per scene image
    std::array<int, 4> image_ids{};               // of each 6-vertex image group
    std::array<bool, hal::OverlayRenderer::kMaxImages> image_present{};  // set by the renderer
    std::vector<BoxVertex> boxes;
    std::size_t boxes_used = 0;
    bool depth = false;  // boxes present: their rects need a depth clear
    RectSet rects;
    hal::DrawnRects drawn;

    void reserve();
    // Fills the arrays and `drawn` for a width x height frame.
    void build(const hal::OverlayScene& scene, const GlyphAtlas& atlas, int width, int height);
};

}  // namespace endotower::gles
