// OverlayScene: what the surgeon-computer interface wants drawn above the video in one
// frame, as a fixed-capacity draw list (filled per frame, never allocates). An
// OverlayRenderer turns it into pixels.
//
// Coordinates are pixels of the video frame (origin top-left, x right, y down);
// 3-D items are millimetres in the endoscope's camera frame (x right, y down, z along
// the view), drawn through `camera`, the calibrated pinhole (eq. 4.28-4.32).
// Colours are straight-alpha RGBA, 0..255. Draw order (later on top): boxes
// (depth-tested among themselves), lines3, images, sectors, quads, lines, discs, texts.
// An `add_*` past capacity returns false and drops the item.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace endotower::hal {

struct Rgba8 {
    std::uint8_t r = 0, g = 0, b = 0, a = 0;
    friend bool operator==(const Rgba8&, const Rgba8&) = default;
};

struct Vec2f {
    float x = 0, y = 0;
};
struct Vec3f {
    float x = 0, y = 0, z = 0;
};

// A rounded rectangle (a button, a panel). border_px 0: no border.
struct SceneQuad {
    float x = 0, y = 0, width = 0, height = 0, corner_px = 0, border_px = 0;
    Rgba8 fill, border;
};
// An annular sector (ring menu item): angles in degrees, 0 = +x, growing clockwise on screen.
struct SceneSector {
    float cx = 0, cy = 0, r_inner = 0, r_outer = 0, start_deg = 0, end_deg = 0, border_px = 0;
    Rgba8 fill, border;
};
// A filled disc or ring (r_inner > 0): the cursor, a dwell-progress ring (sweep_deg < 360
// draws an arc from 12 o'clock, clockwise).
struct SceneDisc {
    float cx = 0, cy = 0, r_inner = 0, r_outer = 0, sweep_deg = 360;
    Rgba8 colour;
};
// A polyline in image pixels; `closed` joins the last point to the first.
struct SceneLine {
    std::array<Vec2f, 64> points{};
    std::size_t count = 0;
    float width_px = 2;
    bool closed = false;
    Rgba8 colour;
};
// A polyline in camera millimetres (the suture thread), projected through the camera.
struct SceneLine3 {
    std::array<Vec3f, 64> points{};
    std::size_t count = 0;
    float width_px = 2;
    Rgba8 colour;
};
// UTF-8 text, `size_px` the line height; anchored at (x, y) by `align`.
struct SceneText {
    enum class Align : std::uint8_t { kTopLeft, kCentre };
    std::array<char, 96> utf8{};  // NUL-terminated
    float x = 0, y = 0, size_px = 24;
    Align align = Align::kTopLeft;
    Rgba8 colour;
};
// An image registered with OverlayRenderer::set_image, scaled into the rectangle; or,
// `warped`, mapped perspective-correctly onto the convex quadrilateral `corners` (pixel
// edges; the image's top-left, top-right, bottom-right, bottom-left), x..height unused:
// an image anchored to tissue moved by a homography. A non-convex quad is not drawn.
struct SceneImage {
    int image_id = 0;
    float x = 0, y = 0, width = 0, height = 0, opacity = 1;
    bool warped = false;
    std::array<Vec2f, 4> corners{};
};
// A cube of edge `size_mm`: camera-from-model transform, column-major 4x4 (mm).
// Faces in the order +x, -x, +y, -y, +z, -z.
struct SceneBox {
    std::array<float, 16> camera_from_model{};
    float size_mm = 40;
    std::array<Rgba8, 6> faces{};
};

// The calibrated endoscope as a pinhole (pixels of the video frame), with the depth range.
struct SceneCamera {
    double fx = 0, fy = 0, cx = 0, cy = 0, near_mm = 5, far_mm = 500;
    bool valid() const { return fx > 0 && fy > 0; }
};

template <typename T, std::size_t N>
struct SceneList {
    std::array<T, N> items{};
    std::size_t count = 0;
    bool add(const T& t) {
        if (count == N) return false;
        items[count++] = t;
        return true;
    }
    const T* begin() const { return items.data(); }
    const T* end() const { return items.data() + count; }
};

struct OverlayScene {
    SceneCamera camera;
    SceneList<SceneBox, 4> boxes;
    SceneList<SceneLine3, 4> lines3;
    SceneList<SceneImage, 4> images;
    SceneList<SceneSector, 32> sectors;
    SceneList<SceneQuad, 48> quads;
    SceneList<SceneLine, 16> lines;
    SceneList<SceneDisc, 16> discs;
    SceneList<SceneText, 48> texts;

    void clear() {
        boxes.count = lines3.count = images.count = sectors.count = quads.count = lines.count =
            discs.count = texts.count = 0;
    }
    bool empty() const {
        return boxes.count + lines3.count + images.count + sectors.count + quads.count +
                   lines.count + discs.count + texts.count ==
               0;
    }
};

}  // namespace endotower::hal
