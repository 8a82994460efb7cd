#include "endotower/gles/gles_renderer.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES2/gl2.h>

#include <cstring>
#include <vector>

#include "composite.hpp"
#include "gl_program.hpp"
#include "glyph_atlas.hpp"
#include "scene_batch.hpp"

namespace endotower::gles {

namespace {

#define ENDOTOWER_HIGHP \
    "#ifdef GL_FRAGMENT_PRECISION_HIGH\nprecision highp float;\n#else\nprecision mediump float;\n#endif\n"

// 2-D items: pixel edges to clip space; GL row 0 is image row 0 (no flip), so
// glReadPixels returns the image's rows in order.
constexpr const char* kShapeVs = R"(
attribute vec2 a_pos;
attribute vec2 a_local;
attribute vec4 a_shape;
attribute vec4 a_shape2;
attribute vec4 a_fill;
attribute vec4 a_border;
uniform vec2 u_scale;
varying vec2 v_local;
varying vec4 v_shape, v_shape2, v_fill, v_border;
void main() {
    v_local = a_local; v_shape = a_shape; v_shape2 = a_shape2; v_fill = a_fill; v_border = a_border;
    gl_Position = vec4(a_pos * u_scale - 1.0, 0.0, 1.0);
}
)";

// Coverage from a signed distance d (pixels, < 0 inside): clamp(0.5 - d) is exact
// for edges on pixel boundaries and a one-pixel ramp otherwise.
// kind 0: rounded rect (half size, corner, border); 1: annular sector (r_in, r_out,
// mid angle, half span; border in shape2.x); 2: segment from the origin to shape.xy,
// half width shape.z.
constexpr const char* kShapeFs = ENDOTOWER_HIGHP R"(
varying vec2 v_local;
varying vec4 v_shape, v_shape2, v_fill, v_border;
void main() {
    float d;
    float bw = 0.0;
    if (v_shape2.w < 0.5) {
        vec2 q = abs(v_local) - v_shape.xy + v_shape.z;
        d = length(max(q, 0.0)) + min(max(q.x, q.y), 0.0) - v_shape.z;
        bw = v_shape.w;
    } else if (v_shape2.w < 1.5) {
        float r = length(v_local);
        d = max(v_shape.x - r, r - v_shape.y);
        if (v_shape.w < 3.1415) {
            float a = atan(v_local.y, v_local.x);
            float delta = mod(a - v_shape.z + 3.14159265, 6.28318531) - 3.14159265;
            d = max(d, (abs(delta) - v_shape.w) * r);
        }
        bw = v_shape2.x;
    } else {
        vec2 ab = v_shape.xy;
        float h = clamp(dot(v_local, ab) / max(dot(ab, ab), 1e-6), 0.0, 1.0);
        d = length(v_local - ab * h) - v_shape.z;
    }
    vec4 c = v_fill;
    if (bw > 0.0) c = mix(v_border, v_fill, clamp(-0.5 - d - bw + 1.0, 0.0, 1.0));
    float a = c.a * clamp(0.5 - d, 0.0, 1.0);
    gl_FragColor = vec4(c.rgb * a, a);
}
)";

constexpr const char* kTexVs = R"(
attribute vec2 a_pos;
attribute vec2 a_uv;
attribute vec4 a_colour;
uniform vec2 u_scale;
varying vec2 v_uv;
varying vec4 v_colour;
void main() {
    v_uv = a_uv; v_colour = a_colour;
    gl_Position = vec4(a_pos * u_scale - 1.0, 0.0, 1.0);
}
)";

// Glyphs: atlas coverage (GL_ALPHA) times the text colour.
constexpr const char* kTextFs = R"(
precision mediump float;
uniform sampler2D u_tex;
varying vec2 v_uv;
varying vec4 v_colour;
void main() {
    float a = texture2D(u_tex, v_uv).a * v_colour.a;
    gl_FragColor = vec4(v_colour.rgb * a, a);
}
)";

// Images: straight-alpha RGBA times the opacity (in v_colour.r).
constexpr const char* kImageFs = R"(
precision mediump float;
uniform sampler2D u_tex;
varying vec2 v_uv;
varying vec4 v_colour;
void main() {
    vec4 c = texture2D(u_tex, v_uv);
    float a = c.a * v_colour.r;
    gl_FragColor = vec4(c.rgb * a, a);
}
)";

// Boxes in camera millimetres through the pinhole's projection; a headlight at the
// camera shades each face by the cosine to the viewer (ambient 0.35).
constexpr const char* kBoxVs = R"(
attribute vec3 a_pos;
attribute vec3 a_normal;
attribute vec4 a_colour;
uniform mat4 u_clip;
varying vec4 v_colour;
void main() {
    float lambert = max(dot(normalize(a_normal), normalize(-a_pos)), 0.0);
    v_colour = vec4(a_colour.rgb * (0.35 + 0.65 * lambert), a_colour.a);
    gl_Position = u_clip * vec4(a_pos, 1.0);
}
)";

constexpr const char* kBoxFs = R"(
precision mediump float;
varying vec4 v_colour;
void main() { gl_FragColor = vec4(v_colour.rgb * v_colour.a, v_colour.a); }
)";

constexpr const char* kShapeAttributes[] = {"a_pos",    "a_local",  "a_shape", "a_shape2",
                                            "a_fill",   "a_border", nullptr};
constexpr const char* kTexAttributes[] = {"a_pos", "a_uv", "a_colour", nullptr};
constexpr const char* kBoxAttributes[] = {"a_pos", "a_normal", "a_colour", nullptr};

void attribute(unsigned slot, int size, std::size_t stride, std::size_t offset) {
    glEnableVertexAttribArray(slot);
    glVertexAttribPointer(slot, size, GL_FLOAT, GL_FALSE, static_cast<GLsizei>(stride),
                          reinterpret_cast<const void*>(offset));
}

class GlesRenderer final : public hal::OverlayRenderer {
public:
    GlesRenderer(EGLDisplay display, EGLContext context, EGLSurface surface,
                 GlesRendererOptions options)
        : display_(display), context_(context), surface_(surface), options_(std::move(options)) {}
    ~GlesRenderer() override;

    std::string_view name() const override { return "gles"; }
    bool configure(int width, int height) override;
    bool set_image(int id, const hal::ImageView& image) override;
    bool render(const hal::OverlayScene& scene, const hal::OverlayLayer& target,
                hal::DrawnRects& drawn) override;
    const std::string& error() const override { return error_; }

private:
    bool fail(const std::string& what) {
        error_ = "gles renderer: " + what;
        return false;
    }
    bool gl_failed(const char* where) {
        const GLenum e = glGetError();
        if (e == GL_NO_ERROR) return false;
        while (glGetError() != GL_NO_ERROR) {
        }
        fail(std::string(where) + ": " + gl_error_text(e));
        return true;
    }
    bool make_current();
    void release_gl();
    void draw(std::size_t first, std::size_t count);

    EGLDisplay display_;
    EGLContext context_;
    EGLSurface surface_;
    GlesRendererOptions options_;
    std::string error_;

    int width_ = 0, height_ = 0;
    bool configured_ = false;
    unsigned fbo_ = 0, colour_ = 0, depth_ = 0, atlas_tex_ = 0;
    unsigned shape_prog_ = 0, text_prog_ = 0, image_prog_ = 0, box_prog_ = 0;
    unsigned shape_vbo_ = 0, text_vbo_ = 0, image_vbo_ = 0, box_vbo_ = 0;
    int box_clip_uniform_ = -1;
    std::array<unsigned, kMaxImages> images_{};
    GlyphAtlas atlas_;
    SceneBatch batch_;
    std::vector<std::uint8_t> staging_;  // read-back of the drawn rects
};

GlesRenderer::~GlesRenderer() {
    if (make_current()) release_gl();
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (surface_ != EGL_NO_SURFACE) eglDestroySurface(display_, surface_);
    eglDestroyContext(display_, context_);
    // The display stays initialised: EGL shares it per process (another renderer or
    // the display driver may use it), and eglTerminate would end their contexts too.
}

bool GlesRenderer::make_current() {
    if (eglGetCurrentContext() == context_) return true;
    if (eglMakeCurrent(display_, surface_, surface_, context_)) return true;
    return fail("eglMakeCurrent: " + egl_error_text(eglGetError()));
}

void GlesRenderer::release_gl() {
    const unsigned programs[] = {shape_prog_, text_prog_, image_prog_, box_prog_};
    for (unsigned p : programs)
        if (p != 0) glDeleteProgram(p);
    const unsigned buffers[] = {shape_vbo_, text_vbo_, image_vbo_, box_vbo_};
    glDeleteBuffers(4, buffers);
    glDeleteTextures(1, &colour_);
    glDeleteTextures(1, &atlas_tex_);
    glDeleteTextures(kMaxImages, images_.data());
    glDeleteRenderbuffers(1, &depth_);
    glDeleteFramebuffers(1, &fbo_);
    shape_prog_ = text_prog_ = image_prog_ = box_prog_ = 0;
    shape_vbo_ = text_vbo_ = image_vbo_ = box_vbo_ = 0;
    colour_ = atlas_tex_ = depth_ = fbo_ = 0;
    images_.fill(0);
    batch_.image_present.fill(false);
    configured_ = false;
}

bool GlesRenderer::configure(int width, int height) {
    if (width <= 0 || height <= 0)
        return fail("configure: invalid size " + std::to_string(width) + "x" + std::to_string(height));
    if (!make_current()) return false;
    release_gl();
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    if (width > max_size || height > max_size)
        return fail("configure: " + std::to_string(width) + "x" + std::to_string(height) +
                    " exceeds GL_MAX_RENDERBUFFER_SIZE " + std::to_string(max_size));
    std::string err;
    if (atlas_.width() == 0 && !atlas_.build(options_.font_path, err)) return fail(err);
    if ((shape_prog_ = link_program(kShapeVs, kShapeFs, kShapeAttributes, err)) == 0 ||
        (text_prog_ = link_program(kTexVs, kTextFs, kTexAttributes, err)) == 0 ||
        (image_prog_ = link_program(kTexVs, kImageFs, kTexAttributes, err)) == 0 ||
        (box_prog_ = link_program(kBoxVs, kBoxFs, kBoxAttributes, err)) == 0)
        return fail(err);
    const float scale[2] = {2.f / static_cast<float>(width), 2.f / static_cast<float>(height)};
    for (unsigned p : {shape_prog_, text_prog_, image_prog_}) {
        glUseProgram(p);
        glUniform2fv(glGetUniformLocation(p, "u_scale"), 1, scale);
        const int tex = glGetUniformLocation(p, "u_tex");
        if (tex >= 0) glUniform1i(tex, 0);
    }
    box_clip_uniform_ = glGetUniformLocation(box_prog_, "u_clip");

    // The render target: RGBA8 colour and a 16-bit depth buffer for the boxes.
    glGenTextures(1, &colour_);
    glBindTexture(GL_TEXTURE_2D, colour_);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
    glGenRenderbuffers(1, &depth_);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, width, height);
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, colour_, 0);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
        return fail("glCheckFramebufferStatus: " + gl_error_text(status));

    glGenTextures(1, &atlas_tex_);
    glBindTexture(GL_TEXTURE_2D, atlas_tex_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_ALPHA, atlas_.width(), atlas_.height(), 0, GL_ALPHA,
                 GL_UNSIGNED_BYTE, atlas_.coverage().data());
    for (GLenum p : {GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER})
        glTexParameteri(GL_TEXTURE_2D, p, GL_LINEAR);
    for (GLenum p : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T})
        glTexParameteri(GL_TEXTURE_2D, p, GL_CLAMP_TO_EDGE);

    batch_.reserve();
    auto make_vbo = [](unsigned& vbo, std::size_t bytes) {
        glGenBuffers(1, &vbo);
        glBindBuffer(GL_ARRAY_BUFFER, vbo);
        glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(bytes), nullptr, GL_STREAM_DRAW);
    };
    make_vbo(shape_vbo_, batch_.shapes.size() * sizeof(ShapeVertex));
    make_vbo(text_vbo_, batch_.text.size() * sizeof(TexVertex));
    make_vbo(image_vbo_, batch_.images.size() * sizeof(TexVertex));
    make_vbo(box_vbo_, batch_.boxes.size() * sizeof(BoxVertex));
    staging_.assign(static_cast<std::size_t>(width) * height * 4, 0);
    if (gl_failed("configure")) return false;
    width_ = width;
    height_ = height;
    configured_ = true;
    return true;
}

bool GlesRenderer::set_image(int id, const hal::ImageView& image) {
    if (id < 0 || id >= kMaxImages)
        return fail("set_image: id " + std::to_string(id) + " outside [0, " +
                    std::to_string(kMaxImages) + ")");
    if (image.width <= 0 || image.height <= 0 || image.rgba == nullptr ||
        image.stride < 4 * image.width)
        return fail("set_image " + std::to_string(id) + ": empty or malformed image (" +
                    std::to_string(image.width) + "x" + std::to_string(image.height) +
                    ", stride " + std::to_string(image.stride) + ")");
    if (!configured_) return fail("set_image before configure");
    if (!make_current()) return false;
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (image.width > max_size || image.height > max_size)
        return fail("set_image " + std::to_string(id) + ": " + std::to_string(image.width) + "x" +
                    std::to_string(image.height) + " exceeds GL_MAX_TEXTURE_SIZE " +
                    std::to_string(max_size));
    // GLES2 has no row length for uploads: pack padded rows first.
    std::vector<std::uint8_t> packed;
    const std::uint8_t* pixels = image.rgba;
    if (image.stride != 4 * image.width) {
        packed.resize(static_cast<std::size_t>(image.width) * image.height * 4);
        for (int y = 0; y < image.height; ++y)
            std::memcpy(&packed[static_cast<std::size_t>(y) * image.width * 4],
                        image.rgba + static_cast<std::ptrdiff_t>(y) * image.stride,
                        static_cast<std::size_t>(image.width) * 4);
        pixels = packed.data();
    }
    unsigned& tex = images_[static_cast<std::size_t>(id)];
    if (tex == 0) glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, image.width, image.height, 0, GL_RGBA,
                 GL_UNSIGNED_BYTE, pixels);
    for (GLenum p : {GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER})
        glTexParameteri(GL_TEXTURE_2D, p, GL_LINEAR);
    for (GLenum p : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T})
        glTexParameteri(GL_TEXTURE_2D, p, GL_CLAMP_TO_EDGE);
    if (gl_failed("set_image: glTexImage2D")) return false;
    batch_.image_present[static_cast<std::size_t>(id)] = true;
    return true;
}

void GlesRenderer::draw(std::size_t first, std::size_t count) {
    glDrawArrays(GL_TRIANGLES, static_cast<GLint>(first), static_cast<GLsizei>(count));
}

bool GlesRenderer::render(const hal::OverlayScene& scene, const hal::OverlayLayer& target,
                          hal::DrawnRects& drawn) {
    drawn.count = 0;
    if (!configured_) return fail("render before configure");
    if (target.width != width_ || target.height != height_ || target.rgba == nullptr ||
        target.stride < 4 * target.width)
        return fail("render: the target layer does not match the configured size");
    if (!make_current()) return false;
    batch_.build(scene, atlas_, width_, height_);
    if (batch_.drawn.count == 0) return true;

    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, width_, height_);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    // Only the drawn rects are cleared (and read): a full-frame clear is what costs a
    // software rasteriser most.
    glClearColor(0, 0, 0, 0);
    glClearDepthf(1);
    glDepthMask(GL_TRUE);
    glEnable(GL_SCISSOR_TEST);
    for (std::size_t i = 0; i < batch_.drawn.count; ++i) {
        const hal::Rect& r = batch_.drawn.rects[i];
        glScissor(r.x, r.y, r.width, r.height);
        glClear(GL_COLOR_BUFFER_BIT | (batch_.depth ? GL_DEPTH_BUFFER_BIT : 0));
    }
    glDisable(GL_SCISSOR_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);  // premultiplied "over"
    glActiveTexture(GL_TEXTURE0);

    if (batch_.boxes_used > 0) {
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glUseProgram(box_prog_);
        const std::array<float, 16> clip = clip_from_camera(scene.camera, width_, height_);
        glUniformMatrix4fv(box_clip_uniform_, 1, GL_FALSE, clip.data());
        glBindBuffer(GL_ARRAY_BUFFER, box_vbo_);
        glBufferSubData(GL_ARRAY_BUFFER, 0,
                        static_cast<GLsizeiptr>(batch_.boxes_used * sizeof(BoxVertex)),
                        batch_.boxes.data());
        attribute(0, 3, sizeof(BoxVertex), offsetof(BoxVertex, x));
        attribute(1, 3, sizeof(BoxVertex), offsetof(BoxVertex, nx));
        attribute(2, 4, sizeof(BoxVertex), offsetof(BoxVertex, colour));
        glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(batch_.boxes_used));
        glDisable(GL_DEPTH_TEST);
    }
    auto bind_shapes = [&] {
        glUseProgram(shape_prog_);
        glBindBuffer(GL_ARRAY_BUFFER, shape_vbo_);
        attribute(0, 2, sizeof(ShapeVertex), offsetof(ShapeVertex, x));
        attribute(1, 2, sizeof(ShapeVertex), offsetof(ShapeVertex, lx));
        attribute(2, 4, sizeof(ShapeVertex), offsetof(ShapeVertex, shape));
        attribute(3, 4, sizeof(ShapeVertex), offsetof(ShapeVertex, shape2));
        attribute(4, 4, sizeof(ShapeVertex), offsetof(ShapeVertex, fill));
        attribute(5, 4, sizeof(ShapeVertex), offsetof(ShapeVertex, border));
    };
    auto bind_tex = [&](unsigned program, unsigned vbo) {
        glUseProgram(program);
        glBindBuffer(GL_ARRAY_BUFFER, vbo);
        glDisableVertexAttribArray(3);
        glDisableVertexAttribArray(4);
        glDisableVertexAttribArray(5);
        attribute(0, 2, sizeof(TexVertex), offsetof(TexVertex, x));
        attribute(1, 2, sizeof(TexVertex), offsetof(TexVertex, u));
        attribute(2, 4, sizeof(TexVertex), offsetof(TexVertex, colour));
    };
    if (batch_.shapes_used > 0) {
        bind_shapes();
        glBufferSubData(GL_ARRAY_BUFFER, 0,
                        static_cast<GLsizeiptr>(batch_.shapes_used * sizeof(ShapeVertex)),
                        batch_.shapes.data());
        if (batch_.lines3_end > 0) draw(0, batch_.lines3_end);
    }
    if (batch_.images_used > 0) {
        bind_tex(image_prog_, image_vbo_);
        glBufferSubData(GL_ARRAY_BUFFER, 0,
                        static_cast<GLsizeiptr>(batch_.images_used * sizeof(TexVertex)),
                        batch_.images.data());
        for (std::size_t i = 0; i < batch_.images_used / 6; ++i) {
            glBindTexture(GL_TEXTURE_2D, images_[static_cast<std::size_t>(batch_.image_ids[i])]);
            draw(6 * i, 6);
        }
    }
    if (batch_.shapes_used > batch_.lines3_end) {
        bind_shapes();
        draw(batch_.lines3_end, batch_.shapes_used - batch_.lines3_end);
    }
    if (batch_.text_used > 0) {
        bind_tex(text_prog_, text_vbo_);
        glBufferSubData(GL_ARRAY_BUFFER, 0,
                        static_cast<GLsizeiptr>(batch_.text_used * sizeof(TexVertex)),
                        batch_.text.data());
        glBindTexture(GL_TEXTURE_2D, atlas_tex_);
        draw(0, batch_.text_used);
    }
    glDisable(GL_BLEND);

    // Read back every rect first: a GL error leaves the target untouched.
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    std::size_t offset = 0;
    for (std::size_t i = 0; i < batch_.drawn.count; ++i) {
        const hal::Rect& r = batch_.drawn.rects[i];
        glReadPixels(r.x, r.y, r.width, r.height, GL_RGBA, GL_UNSIGNED_BYTE, &staging_[offset]);
        offset += static_cast<std::size_t>(r.width) * r.height * 4;
    }
    if (gl_failed("render")) return false;
    offset = 0;
    for (std::size_t i = 0; i < batch_.drawn.count; ++i) {
        const hal::Rect& r = batch_.drawn.rects[i];
        composite_over(&staging_[offset], r.width, r.height,
                       target.rgba + static_cast<std::ptrdiff_t>(r.y) * target.stride + 4 * r.x,
                       target.stride);
        offset += static_cast<std::size_t>(r.width) * r.height * 4;
    }
    drawn = batch_.drawn;
    return true;
}

EGLDisplay open_display(bool& surfaceless) {
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    surfaceless = get_display != nullptr && client != nullptr &&
                  std::strstr(client, "EGL_MESA_platform_surfaceless") != nullptr;
    if (surfaceless) {
        EGLDisplay d = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) return d;
    }
    surfaceless = false;
    EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) return d;
    return EGL_NO_DISPLAY;
}

}  // namespace

std::unique_ptr<hal::OverlayRenderer> create_gles_renderer(std::string& error,
                                                           const GlesRendererOptions& options) {
    bool surfaceless = false;
    EGLDisplay display = open_display(surfaceless);
    if (display == EGL_NO_DISPLAY) {
        error = "gles renderer: eglInitialize: " + egl_error_text(eglGetError()) +
                " (no surfaceless Mesa platform nor default EGL display)";
        return nullptr;
    }
    if (!eglBindAPI(EGL_OPENGL_ES_API)) {
        error = "gles renderer: eglBindAPI(EGL_OPENGL_ES_API): " + egl_error_text(eglGetError());
        return nullptr;
    }
    const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES2_BIT, EGL_SURFACE_TYPE,
                              EGL_PBUFFER_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint n = 0;
    if (!eglChooseConfig(display, attribs, &config, 1, &n) || n == 0) {
        error = "gles renderer: eglChooseConfig: no GLES2 pbuffer config (" +
                egl_error_text(eglGetError()) + ")";
        return nullptr;
    }
    const EGLint ctx_attribs[] = {EGL_CONTEXT_CLIENT_VERSION, 2, EGL_NONE};
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, ctx_attribs);
    if (context == EGL_NO_CONTEXT) {
        error = "gles renderer: eglCreateContext: " + egl_error_text(eglGetError());
        return nullptr;
    }
    // Without EGL_KHR_surfaceless_context a context needs a surface to be current.
    EGLSurface surface = EGL_NO_SURFACE;
    const char* ext = eglQueryString(display, EGL_EXTENSIONS);
    if (ext == nullptr || std::strstr(ext, "EGL_KHR_surfaceless_context") == nullptr) {
        const EGLint pb[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
        surface = eglCreatePbufferSurface(display, config, pb);
        if (surface == EGL_NO_SURFACE) {
            error = "gles renderer: eglCreatePbufferSurface: " + egl_error_text(eglGetError());
            eglDestroyContext(display, context);
            return nullptr;
        }
    }
    if (!eglMakeCurrent(display, surface, surface, context)) {
        error = "gles renderer: eglMakeCurrent: " + egl_error_text(eglGetError());
        if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
        eglDestroyContext(display, context);
        return nullptr;
    }
    return std::make_unique<GlesRenderer>(display, context, surface, options);
}

}  // namespace endotower::gles
