// OverlayLayer: the RGBA layer above the video. Straight (non-premultiplied) alpha,
// bytes R G B A. Only the listed rectangles may hold non-transparent pixels, so a
// CPU compositor touches just those (a KMS overlay plane ignores them).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace endotower::hal {

struct Rect {
    int x = 0, y = 0, width = 0, height = 0;
    bool empty() const { return width <= 0 || height <= 0; }
    friend bool operator==(const Rect&, const Rect&) = default;
};

struct OverlayLayer {
    static constexpr std::size_t kMaxRects = 32;

    int width = 0;
    int height = 0;
    int stride = 0;               // bytes per row, >= 4 * width
    std::uint8_t* rgba = nullptr;  // borrowed; owned by whoever renders the layer
    std::array<Rect, kMaxRects> rects{};
    std::size_t rect_count = 0;   // pixels outside rects[0..rect_count) are transparent

    bool empty() const { return rect_count == 0; }
};

}  // namespace endotower::hal
