// GlesOverlay: draws a hal::OverlayLayer with OpenGL ES 2 into the framebuffer the
// caller has bound (the display's ARGB8888 GBM scanout surface, or an FBO in tests).
//
// Inputs: the layer (straight alpha, bytes R G B A, only layer.rects may be opaque).
// Output: the bound framebuffer cleared to transparent, then the rects drawn with
// premultiplied alpha (rgb * a), which is what a KMS plane's default "Pre-multiplied"
// blend mode expects. Layer row 0 lands on memory row 0 of the target: GL row 0 for
// an FBO (flip_y false), the top row of a window surface such as a GBM scanout
// surface (flip_y true).
// Only the rects are uploaded (GL_EXT_unpack_subimage when present, else row by
// row); nothing is allocated per frame.
// Requires a current GLES2 context for every call, the destructor included.
#pragma once

#include <array>
#include <string>

#include "endotower/hal/overlay.hpp"

namespace endotower::display {

class GlesOverlay {
public:
    GlesOverlay() = default;
    ~GlesOverlay();
    GlesOverlay(const GlesOverlay&) = delete;
    GlesOverlay& operator=(const GlesOverlay&) = delete;

    // Compiles the shaders and creates a width x height texture. False on error.
    bool init(int width, int height, bool flip_y);

    // Draws `layer` (nullptr or empty: fully transparent) into the bound framebuffer
    // of init's size. Parts of the layer outside that size are cut off.
    // buffer_age (EGL_EXT_buffer_age: the target holds what was drawn that many draws
    // ago; 0 = unknown): when known, only the rects of the draws since are cleared,
    // not the whole buffer (a full-screen clear costs a software rasteriser dearly).
    bool draw(const hal::OverlayLayer* layer, int buffer_age = 0);

    int width() const { return width_; }
    int height() const { return height_; }
    const std::string& error() const { return error_; }

private:
    bool fail(const std::string& what);
    void clear(int buffer_age);

    struct Drawn {
        std::array<hal::Rect, hal::OverlayLayer::kMaxRects> rects{};
        std::size_t count = 0;
    };
    static constexpr int kHistory = 4;
    std::array<Drawn, kHistory> history_{};  // [0] = the last draw
    int history_size_ = 0;

    int width_ = 0, height_ = 0;
    unsigned program_ = 0, texture_ = 0, vbo_ = 0;
    int position_attr_ = -1, layer_uniform_ = -1;
    bool flip_y_ = false;
    bool unpack_subimage_ = false;
    std::string error_;
};

}  // namespace endotower::display
