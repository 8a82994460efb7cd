// OverlayCanvas: an RGBA overlay layer that an analysis stage draws into, owning its
// pixels (allocated in configure, never per frame). It tracks the rectangles drawn,
// so clearing and compositing touch only those.
#pragma once

#include <cstdint>
#include <vector>

#include "endotower/hal/overlay.hpp"

namespace endotower::app {

struct Rgba {
    std::uint8_t r = 0, g = 0, b = 0, a = 0;
};

class OverlayCanvas {
public:
    // Allocates width x height RGBA, transparent. Not for the per-frame path.
    void configure(int width, int height);
    int width() const { return layer_.width; }
    int height() const { return layer_.height; }

    // Makes the drawn rectangles transparent again and forgets them.
    void clear();
    // Declares that pixels in `r` (clipped to the canvas) may be non-transparent.
    // Past OverlayLayer::kMaxRects, rectangles are merged into their bounding box.
    void mark(hal::Rect r);
    // Fills `r` with a colour and marks it.
    void fill(hal::Rect r, Rgba c);

    std::uint8_t* row(int y) { return layer_.rgba + static_cast<std::ptrdiff_t>(y) * layer_.stride; }
    const hal::OverlayLayer& layer() const { return layer_; }

private:
    hal::Rect clip(hal::Rect r) const;

    std::vector<std::uint8_t> pixels_;
    hal::OverlayLayer layer_{};
};

}  // namespace endotower::app
