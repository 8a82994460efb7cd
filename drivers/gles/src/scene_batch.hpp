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
#include <cstdint>
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

// Rectangles that overlap are merged (so no pixel is composited twice); past a
// limit the pair whose union grows least is merged.
class RectSet {
public:
    static constexpr std::size_t kCapacity = 256;
    void clear() { count_ = 0; }
    void add(const hal::Rect& r);  // clipped by the caller
    // Merges down to at most `max` rects, copied to out[0, count).
    void finish(hal::Rect* out, std::size_t& count, std::size_t max);

private:
    void merge_into(std::size_t keep, std::size_t drop);
    std::array<hal::Rect, kCapacity> rects_{};
    std::size_t count_ = 0;
};

// clip_from_camera for the pinhole (eq. 4.28-4.32), column-major, for a
// width x height target whose GL row 0 is image row 0.
std::array<float, 16> clip_from_camera(const hal::SceneCamera& camera, int width, int height);

// The draw lists in scene order; each shape list has its own GL program.
enum DrawList : std::uint8_t { kLines3, kImages, kSectors, kQuads, kLines, kDiscs, kTexts, kBoxes, kListCount };

// One item: its vertices in its list's array and the screen rect it may touch.
struct BatchItem {
    DrawList list = kQuads;
    std::uint32_t first = 0, count = 0;
    hal::Rect rect;
    std::size_t region = 0;  // the region that contains `rect`
};

struct SceneBatch {
    static constexpr std::size_t kMaxItems = 2048;
    // As built, in scene order.
    std::vector<ShapeVertex> shapes;
    std::vector<TexVertex> text, images;
    std::vector<BoxVertex> boxes;
    std::size_t shapes_used = 0, text_used = 0, images_used = 0, boxes_used = 0;
    std::vector<BatchItem> items;
    std::size_t items_used = 0;
    std::array<bool, hal::OverlayRenderer::kMaxImages> image_present{};  // set by the renderer
    std::array<std::uint64_t, hal::OverlayRenderer::kMaxImages> image_version{};  // by the renderer
    RectSet rects;
    // Regions: disjoint rects, each item inside one; the renderer clears, draws, reads
    // back, caches and composites by region. `drawn` (what render() reports) merges
    // them further into the contract's 16.
    static constexpr std::size_t kMaxRegions = 64;
    std::array<hal::Rect, kMaxRegions> regions{};
    std::size_t region_count = 0;
    std::array<std::uint64_t, kMaxRegions> region_hash{};  // of everything drawn into it
    hal::DrawnRects drawn;

    // What to draw this frame (select()): the items of the chosen rects, same order.
    std::vector<ShapeVertex> draw_shapes;
    std::vector<TexVertex> draw_text, draw_images;
    std::vector<BoxVertex> draw_boxes;
    std::array<std::size_t, kListCount + 1> shape_range{};  // draw_shapes of list l: [l], [l+1])
    std::size_t draw_text_used = 0, draw_images_used = 0, draw_boxes_used = 0;
    std::array<int, 4> draw_image_ids{};  // of each 6-vertex group of draw_images

    void reserve();
    // Fills the arrays, the regions and `drawn` for a width x height frame.
    void build(const hal::OverlayScene& scene, const GlyphAtlas& atlas, int width, int height);
    // Gathers the items of the regions with redraw[i] into the draw_* arrays.
    void select(const std::array<bool, kMaxRegions>& redraw);
};

}  // namespace endotower::gles
