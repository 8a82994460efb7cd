// GlesRenderer: hal::OverlayRenderer with OpenGL ES 2 through EGL. It owns its EGL
// display and context: Mesa's surfaceless platform (llvmpipe on the host, the GPU's
// render node on a board), else the default display with a 1x1 pbuffer.
//
// configure(width, height) creates the offscreen framebuffer (RGBA8 colour, 16-bit
// depth) of the video frame's size and the glyph atlas (FreeType, `font_path`, line
// heights 10..64 px). render() draws the scene into the framebuffer with premultiplied
// alpha, reads back only the regions it touched (glReadPixels) and composites them
// "over" the target's straight-alpha pixels on the CPU; every other target pixel is
// left bit for bit. Regions unchanged since the last render() are not drawn or read
// again (a standing menu costs only its composite). It allocates nothing (vertex and
// staging buffers are sized in configure).
//
// Coordinates: 2-D items in pixel edges (a quad at x=10, width 20 covers pixels
// 10..29); 3-D items through the pinhole u = fx X/Z + cx, v = fy Y/Z + cy (eq. 4.28)
// with OpenCV's convention (pixel centres at integers), the GL projection built from
// it (eq. 4.29-4.32). Colour accuracy: the 8-bit premultiplied framebuffer rounds,
// so a composited channel is within 1 + 128/alpha of the exact "over" (docs/rendering.md).
//
// Errors: configure/set_image/render return false and error() names the EGL/GL call
// and its code (or the font file and FreeType error).
// Threading: every call on one thread; the context is made current on it.
#pragma once

#include <memory>
#include <string>

#include "endotower/hal/overlay_renderer.hpp"

namespace endotower::gles {

struct GlesRendererOptions {
    std::string font_path = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
};

// Opens the EGL display and a GLES2 context. nullptr with `error` set when no EGL
// display or GLES2 context can be had (no Mesa, no GPU node).
std::unique_ptr<hal::OverlayRenderer> create_gles_renderer(std::string& error,
                                                           const GlesRendererOptions& options = {});

}  // namespace endotower::gles
