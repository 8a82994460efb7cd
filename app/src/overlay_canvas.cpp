#include "endotower/app/overlay_canvas.hpp"

#include <algorithm>
#include <cstring>

namespace endotower::app {

void OverlayCanvas::configure(int width, int height) {
    pixels_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4, 0);
    layer_ = hal::OverlayLayer{};
    layer_.width = width;
    layer_.height = height;
    layer_.stride = width * 4;
    layer_.rgba = pixels_.data();
}

hal::Rect OverlayCanvas::clip(hal::Rect r) const {
    const int x0 = std::max(r.x, 0), y0 = std::max(r.y, 0);
    const int x1 = std::min(r.x + r.width, layer_.width);
    const int y1 = std::min(r.y + r.height, layer_.height);
    if (x1 <= x0 || y1 <= y0) return {};
    return {x0, y0, x1 - x0, y1 - y0};
}

void OverlayCanvas::clear() {
    for (std::size_t i = 0; i < layer_.rect_count; ++i) {
        const hal::Rect& r = layer_.rects[i];
        for (int y = r.y; y < r.y + r.height; ++y)
            std::memset(row(y) + static_cast<std::ptrdiff_t>(r.x) * 4, 0,
                        static_cast<std::size_t>(r.width) * 4);
    }
    layer_.rect_count = 0;
}

void OverlayCanvas::mark(hal::Rect r) {
    r = clip(r);
    if (r.empty()) return;
    for (std::size_t i = 0; i < layer_.rect_count; ++i) {
        const hal::Rect& o = layer_.rects[i];
        if (r.x >= o.x && r.y >= o.y && r.x + r.width <= o.x + o.width &&
            r.y + r.height <= o.y + o.height)
            return;  // already covered
    }
    if (layer_.rect_count < hal::OverlayLayer::kMaxRects) {
        layer_.rects[layer_.rect_count++] = r;
        return;
    }
    // Full: grow the last rectangle to cover the new one. Coarser, never wrong.
    hal::Rect& last = layer_.rects[layer_.rect_count - 1];
    const int x0 = std::min(last.x, r.x), y0 = std::min(last.y, r.y);
    const int x1 = std::max(last.x + last.width, r.x + r.width);
    const int y1 = std::max(last.y + last.height, r.y + r.height);
    last = {x0, y0, x1 - x0, y1 - y0};
}

void OverlayCanvas::fill(hal::Rect r, Rgba c) {
    r = clip(r);
    if (r.empty()) return;
    for (int y = r.y; y < r.y + r.height; ++y) {
        std::uint8_t* p = row(y) + static_cast<std::ptrdiff_t>(r.x) * 4;
        for (int x = 0; x < r.width; ++x, p += 4) {
            p[0] = c.r;
            p[1] = c.g;
            p[2] = c.b;
            p[3] = c.a;
        }
    }
    mark(r);
}

}  // namespace endotower::app
