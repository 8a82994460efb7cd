// OverlayRenderer: draws an OverlayScene into the RGBA overlay layer (OpenGL ES 2
// through EGL on the board and headless on the host; drivers/ provide it).
//
// Threading: every call from one thread (the analysis thread), which owns the GL
// context. configure() and set_image() allocate and may be slow: call them off the
// per-frame path. render() allocates nothing.
// Ownership: the target layer's pixels are borrowed for the call.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "endotower/hal/overlay.hpp"
#include "endotower/hal/overlay_scene.hpp"

namespace endotower::hal {

// A borrowed RGBA image (straight alpha), rows `stride` bytes apart.
struct ImageView {
    int width = 0, height = 0, stride = 0;
    const std::uint8_t* rgba = nullptr;
};

// The rectangles render() wrote; past capacity they merge into their bounding box.
struct DrawnRects {
    std::array<Rect, 16> rects{};
    std::size_t count = 0;
};

class OverlayRenderer {
public:
    static constexpr int kMaxImages = 8;
    virtual ~OverlayRenderer() = default;
    virtual std::string_view name() const = 0;

    // Sizes the render target to the video frame. False on error (see error()).
    virtual bool configure(int width, int height) = 0;
    // Stores `image` (copied) under `id` in [0, kMaxImages), replacing what was there.
    virtual bool set_image(int id, const ImageView& image) = 0;

    // Composites `scene` over the existing pixels of `target` (straight alpha "over")
    // and reports the rectangles it touched in `drawn`; pixels outside them are left
    // exactly as they were. target.width/height must equal the configured size.
    // False on a GL error (see error()); the target is then unchanged.
    virtual bool render(const OverlayScene& scene, const OverlayLayer& target,
                        DrawnRects& drawn) = 0;

    virtual const std::string& error() const = 0;
};

}  // namespace endotower::hal
