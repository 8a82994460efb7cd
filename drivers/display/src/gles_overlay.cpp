#include "endotower/display/gles_overlay.hpp"

#include <GLES2/gl2.h>
#include <GLES2/gl2ext.h>

#include <algorithm>
#include <cstring>

namespace endotower::display {

namespace {

// Texture coordinates come straight from the position, so layer row 0 (texel row 0)
// is drawn at GL y = 0, or at the top (GL y = height - 1) with flip = -1.
constexpr const char* kVertexShader = R"(
attribute vec2 position;
uniform float flip;
varying vec2 uv;
void main() {
    uv = position * 0.5 + 0.5;
    gl_Position = vec4(position.x, position.y * flip, 0.0, 1.0);
}
)";

// Straight alpha in, premultiplied out.
constexpr const char* kFragmentShader = R"(
precision mediump float;
varying vec2 uv;
uniform sampler2D layer;
void main() {
    vec4 c = texture2D(layer, uv);
    gl_FragColor = vec4(c.rgb * c.a, c.a);
}
)";

unsigned compile(unsigned type, const char* source, std::string& log) {
    const unsigned s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char buf[512] = {};
        glGetShaderInfoLog(s, sizeof buf, nullptr, buf);
        log = buf;
        glDeleteShader(s);
        return 0;
    }
    return s;
}

}  // namespace

GlesOverlay::~GlesOverlay() {
    if (program_ != 0) glDeleteProgram(program_);
    if (texture_ != 0) glDeleteTextures(1, &texture_);
    if (vbo_ != 0) glDeleteBuffers(1, &vbo_);
}

bool GlesOverlay::fail(const std::string& what) {
    error_ = "GLES overlay: " + what;
    return false;
}

bool GlesOverlay::init(int width, int height, bool flip_y) {
    if (width <= 0 || height <= 0) return fail("invalid size");
    flip_y_ = flip_y;
    width_ = width;
    height_ = height;
    const char* ext = reinterpret_cast<const char*>(glGetString(GL_EXTENSIONS));
    if (ext == nullptr) return fail("no current GLES context");
    unpack_subimage_ = std::strstr(ext, "GL_EXT_unpack_subimage") != nullptr;

    std::string log;
    const unsigned vs = compile(GL_VERTEX_SHADER, kVertexShader, log);
    if (vs == 0) return fail("vertex shader: " + log);
    const unsigned fs = compile(GL_FRAGMENT_SHADER, kFragmentShader, log);
    if (fs == 0) {
        glDeleteShader(vs);
        return fail("fragment shader: " + log);
    }
    program_ = glCreateProgram();
    glAttachShader(program_, vs);
    glAttachShader(program_, fs);
    glLinkProgram(program_);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program_, GL_LINK_STATUS, &ok);
    if (!ok) return fail("shader program does not link");
    position_attr_ = glGetAttribLocation(program_, "position");
    layer_uniform_ = glGetUniformLocation(program_, "layer");
    glUseProgram(program_);
    glUniform1f(glGetUniformLocation(program_, "flip"), flip_y ? -1.f : 1.f);

    static constexpr float kQuad[] = {-1.f, -1.f, 1.f, -1.f, -1.f, 1.f, 1.f, 1.f};
    glGenBuffers(1, &vbo_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glBufferData(GL_ARRAY_BUFFER, sizeof kQuad, kQuad, GL_STATIC_DRAW);

    glGenTextures(1, &texture_);
    glBindTexture(GL_TEXTURE_2D, texture_);
    // Texels map 1:1 onto pixels: nearest keeps them exact.
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
    if (glGetError() != GL_NO_ERROR) return fail("cannot create the overlay texture");
    return true;
}

void GlesOverlay::clear(int buffer_age) {
    glClearColor(0.f, 0.f, 0.f, 0.f);
    if (buffer_age < 1 || buffer_age > history_size_) {
        glDisable(GL_SCISSOR_TEST);
        glClear(GL_COLOR_BUFFER_BIT);
        return;
    }
    // The buffer still shows the draw of `buffer_age` ago; everything drawn since then
    // (in other buffers) covers the rects that may be stale here.
    glEnable(GL_SCISSOR_TEST);
    for (int k = 0; k < buffer_age; ++k)
        for (std::size_t i = 0; i < history_[static_cast<std::size_t>(k)].count; ++i) {
            const hal::Rect& r = history_[static_cast<std::size_t>(k)].rects[i];
            glScissor(r.x, flip_y_ ? height_ - r.y - r.height : r.y, r.width, r.height);
            glClear(GL_COLOR_BUFFER_BIT);
        }
    glDisable(GL_SCISSOR_TEST);
}

bool GlesOverlay::draw(const hal::OverlayLayer* layer, int buffer_age) {
    glViewport(0, 0, width_, height_);
    glDisable(GL_BLEND);
    clear(buffer_age);
    // This draw becomes history_[0].
    for (int k = kHistory - 1; k > 0; --k)
        history_[static_cast<std::size_t>(k)] = history_[static_cast<std::size_t>(k - 1)];
    history_[0].count = 0;
    history_size_ = std::min(history_size_ + 1, kHistory);
    if (layer == nullptr || layer->empty() || layer->rgba == nullptr)
        return glGetError() == GL_NO_ERROR || fail("clear failed");

    const int w = std::min(width_, layer->width), h = std::min(height_, layer->height);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    // Upload only the rects; pixels outside them are never read by the draw below.
    hal::Rect clipped[hal::OverlayLayer::kMaxRects];
    std::size_t n = 0;
    for (std::size_t i = 0; i < layer->rect_count && i < hal::OverlayLayer::kMaxRects; ++i) {
        const hal::Rect& r = layer->rects[i];
        const int x0 = std::max(0, r.x), y0 = std::max(0, r.y);
        const int x1 = std::min(w, r.x + r.width), y1 = std::min(h, r.y + r.height);
        if (x1 <= x0 || y1 <= y0) continue;
        clipped[n++] = {x0, y0, x1 - x0, y1 - y0};
        history_[0].rects[history_[0].count++] = clipped[n - 1];
        const std::uint8_t* first =
            layer->rgba + static_cast<std::ptrdiff_t>(y0) * layer->stride + 4 * x0;
        if (unpack_subimage_ && layer->stride % 4 == 0) {
            glPixelStorei(GL_UNPACK_ROW_LENGTH_EXT, layer->stride / 4);
            glTexSubImage2D(GL_TEXTURE_2D, 0, x0, y0, x1 - x0, y1 - y0, GL_RGBA, GL_UNSIGNED_BYTE,
                            first);
            glPixelStorei(GL_UNPACK_ROW_LENGTH_EXT, 0);
        } else {
            for (int y = y0; y < y1; ++y)
                glTexSubImage2D(GL_TEXTURE_2D, 0, x0, y, x1 - x0, 1, GL_RGBA, GL_UNSIGNED_BYTE,
                                first + static_cast<std::ptrdiff_t>(y - y0) * layer->stride);
        }
    }

    glUseProgram(program_);
    glActiveTexture(GL_TEXTURE0);
    glUniform1i(layer_uniform_, 0);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glEnableVertexAttribArray(static_cast<unsigned>(position_attr_));
    glVertexAttribPointer(static_cast<unsigned>(position_attr_), 2, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnable(GL_SCISSOR_TEST);
    for (std::size_t i = 0; i < n; ++i) {
        const hal::Rect& r = clipped[i];
        glScissor(r.x, flip_y_ ? height_ - r.y - r.height : r.y, r.width, r.height);
        glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    }
    glDisable(GL_SCISSOR_TEST);
    return glGetError() == GL_NO_ERROR || fail("drawing the overlay failed");
}

}  // namespace endotower::display
