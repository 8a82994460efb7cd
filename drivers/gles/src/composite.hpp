// Straight-alpha "over" of a premultiplied source (the renderer's read-back) onto a
// straight-alpha RGBA target, on the CPU. Source pixels with alpha 0 leave the
// target untouched, bit for bit. No allocation.
#pragma once

#include <cstdint>

namespace endotower::gles {

// src: width x height premultiplied RGBA, rows packed (4 * width bytes).
// dst: the target's first pixel of the same rectangle, rows `dst_stride` bytes apart.
void composite_over(const std::uint8_t* src, int width, int height, std::uint8_t* dst,
                    int dst_stride);

}  // namespace endotower::gles
