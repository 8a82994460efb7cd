// CPU compositor: what a display controller does with an overlay plane, done on the
// CPU for the file sink and the benchmark. Straight-alpha "over":
//   out = (a * overlay + (255 - a) * video + 127) / 255, per channel,
// computed only inside the layer's rectangles; elsewhere the output is a copy of the
// video, bit for bit (and so is any pixel whose alpha is 0).
#pragma once

#include <cstdint>

#include "endotower/hal/frame.hpp"
#include "endotower/hal/overlay.hpp"

namespace endotower::sim {

// Copies `video` (BGR24 or BGRA32) into `out` (same format, `out_stride` bytes per row)
// and blends `overlay` (same width/height as the video; nullptr = none) on top.
// False if the formats do not match. Allocates nothing.
bool compose(const hal::Frame& video, const hal::OverlayLayer* overlay, std::uint8_t* out,
             int out_stride);

// Blends in place into a BGR24/BGRA32 image; the same arithmetic as compose().
bool blend_in_place(const hal::FrameFormat& format, std::uint8_t* pixels,
                    const hal::OverlayLayer& overlay);

}  // namespace endotower::sim
