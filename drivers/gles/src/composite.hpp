// The CPU side of the overlay composite: the read-back (premultiplied, as GL blends)
// turned into straight alpha once, when it is read, then composited "over" a
// straight-alpha RGBA target every frame. No allocation.
#pragma once

#include <cstddef>
#include <cstdint>

namespace endotower::gles {

// In place: c = round(c * 255 / a) for `count` RGBA pixels (a = 0: all zero).
void unpremultiply(std::uint8_t* rgba, std::size_t count);

// src: width x height straight-alpha RGBA, rows packed (4 * width bytes).
// dst: the target's first pixel of the same rectangle, rows `dst_stride` bytes apart.
// Source alpha 0 leaves the target pixel bit for bit; alpha 255 or a transparent
// target pixel takes the source as it is; otherwise the exact "over", rounded.
// dst_transparent: the caller knows every target pixel here has alpha 0 (outside the
// layer's rects), so the target is not read, only written where the source shows.
void composite_over(const std::uint8_t* src, int width, int height, std::uint8_t* dst,
                    int dst_stride, bool dst_transparent);

}  // namespace endotower::gles
