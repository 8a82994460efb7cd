#include "endotower/gles/gles_renderer.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES2/gl2.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "composite.hpp"
#include "gl_program.hpp"
#include "glyph_atlas.hpp"
#include "scene_batch.hpp"

namespace endotower::gles {

namespace {

#define ENDOTOWER_HIGHP                                                                    \
    "#ifdef GL_FRAGMENT_PRECISION_HIGH\nprecision highp float;\n#else\nprecision mediump " \
    "float;\n#endif\n"

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
// for edges on pixel boundaries and a one-pixel ramp otherwise. One program per shape
// kind: llvmpipe runs both sides of a branch, so a shared shader would pay for all.
#define ENDOTOWER_SHAPE_HEAD \
    ENDOTOWER_HIGHP "varying vec2 v_local;\nvarying vec4 v_shape, v_shape2, v_fill, v_border;\n"
#define ENDOTOWER_SHAPE_TAIL                                                                   \
    "    vec4 c = bw > 0.0 ? mix(v_border, v_fill, clamp(0.5 - d - bw, 0.0, 1.0)) : v_fill;\n" \
    "    float a = c.a * clamp(0.5 - d, 0.0, 1.0);\n"                                          \
    "    gl_FragColor = vec4(c.rgb * a, a);\n}\n"

// Rounded rect: half size, corner radius, border width.
constexpr const char* kRoundedRectFs = ENDOTOWER_SHAPE_HEAD R"(
void main() {
    vec2 q = abs(v_local) - v_shape.xy + v_shape.z;
    float d = length(max(q, 0.0)) + min(max(q.x, q.y), 0.0) - v_shape.z;
    float bw = v_shape.w;
)" ENDOTOWER_SHAPE_TAIL;

// Annular sector: r_in, r_out, border, mode (0 full ring, 1 span <= 180 deg: inside
// both half-planes, 2 wider: inside either); shape2 the half-planes' outward normals.
constexpr const char* kSectorFs = ENDOTOWER_SHAPE_HEAD R"(
void main() {
    float r = length(v_local);
    float d = max(v_shape.x - r, r - v_shape.y);
    float d1 = dot(v_local, v_shape2.xy), d2 = dot(v_local, v_shape2.zw);
    float da = v_shape.w > 1.5 ? min(d1, d2) : max(d1, d2);
    d = v_shape.w > 0.5 ? max(d, da) : d;
    float bw = v_shape.z;
)" ENDOTOWER_SHAPE_TAIL;

// Segment from the origin to shape.xy, half width shape.z (round caps).
constexpr const char* kSegmentFs = ENDOTOWER_SHAPE_HEAD R"(
void main() {
    vec2 ab = v_shape.xy;
    float h = clamp(dot(v_local, ab) / max(dot(ab, ab), 1e-6), 0.0, 1.0);
    float d = length(v_local - ab * h) - v_shape.z;
    float bw = 0.0;
)" ENDOTOWER_SHAPE_TAIL;

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

// Images: straight-alpha RGBA times the opacity (in v_colour.r); the texture
// coordinate is projective, uv / q with q in v_colour.b (1 for a rectangle, the
// homography's for a warped quad: perspective-correct).
constexpr const char* kImageFs = ENDOTOWER_HIGHP R"(
uniform sampler2D u_tex;
varying vec2 v_uv;
varying vec4 v_colour;
void main() {
    vec4 c = texture2D(u_tex, v_uv / v_colour.b);
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

constexpr const char* kShapeAttributes[] = {"a_pos",  "a_local",  "a_shape", "a_shape2",
                                            "a_fill", "a_border", nullptr};
constexpr const char* kTexAttributes[] = {"a_pos", "a_uv", "a_colour", nullptr};
constexpr const char* kBoxAttributes[] = {"a_pos", "a_normal", "a_colour", nullptr};

long long area_of(const hal::Rect& r) {
    return static_cast<long long>(r.width) * r.height;
}

void attribute(unsigned slot, int size, std::size_t stride, std::size_t offset) {
    glEnableVertexAttribArray(slot);
    // With a bound vertex buffer GLES takes the byte offset in the pointer argument.
    glVertexAttribPointer(
        slot, size, GL_FLOAT, GL_FALSE, static_cast<GLsizei>(stride),
        reinterpret_cast<const void*>(offset));  // NOLINT(performance-no-int-to-ptr)
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

    EGLDisplay display_;
    EGLContext context_;
    EGLSurface surface_;
    GlesRendererOptions options_;
    std::string error_;

    int width_ = 0, height_ = 0;
    bool configured_ = false;
    unsigned fbo_ = 0, colour_ = 0, depth_ = 0, atlas_tex_ = 0;
    unsigned rrect_prog_ = 0, sector_prog_ = 0, segment_prog_ = 0;
    unsigned text_prog_ = 0, image_prog_ = 0, box_prog_ = 0;
    unsigned shape_vbo_ = 0, text_vbo_ = 0, image_vbo_ = 0, box_vbo_ = 0;
    int box_clip_uniform_ = -1;
    std::array<unsigned, kMaxImages> images_{};
    GlyphAtlas atlas_;
    SceneBatch batch_;
    std::vector<std::uint8_t> staging_;  // read-back of the drawn rects

    // Last frame's rects: what they showed (hash) and where their read-back lies in
    // staging_. A rect drawn again with the same hash is still in the framebuffer and
    // in staging_, so it is neither drawn nor read again (a menu that stands still).
    struct Cache {
        std::array<hal::Rect, SceneBatch::kMaxRegions> rects{};
        std::array<std::uint64_t, SceneBatch::kMaxRegions> hash{};
        std::array<std::size_t, SceneBatch::kMaxRegions> offset{};
        std::size_t count = 0;
    } cache_;
    void draw_dirty(const hal::OverlayScene& scene,
                    const std::array<bool, SceneBatch::kMaxRegions>& redraw);
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
    const unsigned programs[] = {rrect_prog_, sector_prog_, segment_prog_,
                                 text_prog_,  image_prog_,  box_prog_};
    for (unsigned p : programs)
        if (p != 0) glDeleteProgram(p);
    const unsigned buffers[] = {shape_vbo_, text_vbo_, image_vbo_, box_vbo_};
    glDeleteBuffers(4, buffers);
    glDeleteTextures(1, &colour_);
    glDeleteTextures(1, &atlas_tex_);
    glDeleteTextures(kMaxImages, images_.data());
    glDeleteRenderbuffers(1, &depth_);
    glDeleteFramebuffers(1, &fbo_);
    rrect_prog_ = sector_prog_ = segment_prog_ = text_prog_ = image_prog_ = box_prog_ = 0;
    cache_.count = 0;
    shape_vbo_ = text_vbo_ = image_vbo_ = box_vbo_ = 0;
    colour_ = atlas_tex_ = depth_ = fbo_ = 0;
    images_.fill(0);
    batch_.image_present.fill(false);
    configured_ = false;
}

bool GlesRenderer::configure(int width, int height) {
    if (width <= 0 || height <= 0)
        return fail("configure: invalid size " + std::to_string(width) + "x" +
                    std::to_string(height));
    if (!make_current()) return false;
    release_gl();
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    if (width > max_size || height > max_size)
        return fail("configure: " + std::to_string(width) + "x" + std::to_string(height) +
                    " exceeds GL_MAX_RENDERBUFFER_SIZE " + std::to_string(max_size));
    std::string err;
    if (atlas_.width() == 0 && !atlas_.build(options_.font_path, err)) return fail(err);
    if ((rrect_prog_ = link_program(kShapeVs, kRoundedRectFs, kShapeAttributes, err)) == 0 ||
        (sector_prog_ = link_program(kShapeVs, kSectorFs, kShapeAttributes, err)) == 0 ||
        (segment_prog_ = link_program(kShapeVs, kSegmentFs, kShapeAttributes, err)) == 0 ||
        (text_prog_ = link_program(kTexVs, kTextFs, kTexAttributes, err)) == 0 ||
        (image_prog_ = link_program(kTexVs, kImageFs, kTexAttributes, err)) == 0 ||
        (box_prog_ = link_program(kBoxVs, kBoxFs, kBoxAttributes, err)) == 0)
        return fail(err);
    const float scale[2] = {2.f / static_cast<float>(width), 2.f / static_cast<float>(height)};
    for (unsigned p : {rrect_prog_, sector_prog_, segment_prog_, text_prog_, image_prog_}) {
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
    // Twice the frame: the rects kept from the last frame stay where they are.
    staging_.assign(static_cast<std::size_t>(width) * height * 8, 0);
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
                    std::to_string(image.width) + "x" + std::to_string(image.height) + ", stride " +
                    std::to_string(image.stride) + ")");
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
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, image.width, image.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                 pixels);
    for (GLenum p : {GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER})
        glTexParameteri(GL_TEXTURE_2D, p, GL_LINEAR);
    for (GLenum p : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T})
        glTexParameteri(GL_TEXTURE_2D, p, GL_CLAMP_TO_EDGE);
    if (gl_failed("set_image: glTexImage2D")) return false;
    batch_.image_present[static_cast<std::size_t>(id)] = true;
    ++batch_.image_version[static_cast<std::size_t>(id)];
    return true;
}

void GlesRenderer::draw_dirty(const hal::OverlayScene& scene,
                              const std::array<bool, SceneBatch::kMaxRegions>& redraw) {
    batch_.select(redraw);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, width_, height_);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    // Only the rects drawn again are cleared: a full-frame clear is what costs a
    // software rasteriser most.
    glClearColor(0, 0, 0, 0);
    glClearDepthf(1);
    glDepthMask(GL_TRUE);
    glEnable(GL_SCISSOR_TEST);
    for (std::size_t i = 0; i < batch_.region_count; ++i) {
        if (!redraw[i]) continue;
        const hal::Rect& r = batch_.regions[i];
        glScissor(r.x, r.y, r.width, r.height);
        glClear(GL_COLOR_BUFFER_BIT | (batch_.draw_boxes_used > 0 ? GL_DEPTH_BUFFER_BIT : 0));
    }
    glDisable(GL_SCISSOR_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);  // premultiplied "over"
    glActiveTexture(GL_TEXTURE0);

    if (batch_.draw_boxes_used > 0) {
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glUseProgram(box_prog_);
        const std::array<float, 16> clip = clip_from_camera(scene.camera, width_, height_);
        glUniformMatrix4fv(box_clip_uniform_, 1, GL_FALSE, clip.data());
        glBindBuffer(GL_ARRAY_BUFFER, box_vbo_);
        glBufferSubData(GL_ARRAY_BUFFER, 0,
                        static_cast<GLsizeiptr>(batch_.draw_boxes_used * sizeof(BoxVertex)),
                        batch_.draw_boxes.data());
        attribute(0, 3, sizeof(BoxVertex), offsetof(BoxVertex, x));
        attribute(1, 3, sizeof(BoxVertex), offsetof(BoxVertex, nx));
        attribute(2, 4, sizeof(BoxVertex), offsetof(BoxVertex, colour));
        glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(batch_.draw_boxes_used));
        glDisable(GL_DEPTH_TEST);
    }
    const std::size_t shapes = batch_.shape_range[kListCount];
    auto shape_list = [&](DrawList list, unsigned program) {
        const std::size_t first = batch_.shape_range[list],
                          n = batch_.shape_range[list + 1] - first;
        if (n == 0) return;
        glUseProgram(program);
        glBindBuffer(GL_ARRAY_BUFFER, shape_vbo_);
        attribute(0, 2, sizeof(ShapeVertex), offsetof(ShapeVertex, x));
        attribute(1, 2, sizeof(ShapeVertex), offsetof(ShapeVertex, lx));
        attribute(2, 4, sizeof(ShapeVertex), offsetof(ShapeVertex, shape));
        attribute(3, 4, sizeof(ShapeVertex), offsetof(ShapeVertex, shape2));
        attribute(4, 4, sizeof(ShapeVertex), offsetof(ShapeVertex, fill));
        attribute(5, 4, sizeof(ShapeVertex), offsetof(ShapeVertex, border));
        glDrawArrays(GL_TRIANGLES, static_cast<GLint>(first), static_cast<GLsizei>(n));
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
    if (shapes > 0) {
        glBindBuffer(GL_ARRAY_BUFFER, shape_vbo_);
        glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(shapes * sizeof(ShapeVertex)),
                        batch_.draw_shapes.data());
    }
    shape_list(kLines3, segment_prog_);
    if (batch_.draw_images_used > 0) {
        bind_tex(image_prog_, image_vbo_);
        glBufferSubData(GL_ARRAY_BUFFER, 0,
                        static_cast<GLsizeiptr>(batch_.draw_images_used * sizeof(TexVertex)),
                        batch_.draw_images.data());
        for (std::size_t i = 0; i < batch_.draw_images_used / 6; ++i) {
            glBindTexture(GL_TEXTURE_2D,
                          images_[static_cast<std::size_t>(batch_.draw_image_ids[i])]);
            glDrawArrays(GL_TRIANGLES, static_cast<GLint>(6 * i), 6);
        }
    }
    shape_list(kSectors, sector_prog_);
    shape_list(kQuads, rrect_prog_);
    shape_list(kLines, segment_prog_);
    shape_list(kDiscs, sector_prog_);
    if (batch_.draw_text_used > 0) {
        bind_tex(text_prog_, text_vbo_);
        glBufferSubData(GL_ARRAY_BUFFER, 0,
                        static_cast<GLsizeiptr>(batch_.draw_text_used * sizeof(TexVertex)),
                        batch_.draw_text.data());
        glBindTexture(GL_TEXTURE_2D, atlas_tex_);
        glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(batch_.draw_text_used));
    }
    glDisable(GL_BLEND);
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
    const std::size_t n = batch_.region_count;
    const auto& regions = batch_.regions;

    // Regions unchanged since the last frame keep their pixels and read-back; the others
    // are drawn and read back after the kept ones' staging, or, when that would not
    // fit, everything is read back from the start of staging_.
    std::array<bool, SceneBatch::kMaxRegions> redraw{}, read{};
    std::array<std::size_t, SceneBatch::kMaxRegions> offset{};
    std::size_t end = 0;
    bool any_redraw = false;
    for (std::size_t i = 0; i < n; ++i) {
        redraw[i] = read[i] = true;
        for (std::size_t j = 0; j < cache_.count; ++j)
            if (cache_.rects[j] == regions[i] && cache_.hash[j] == batch_.region_hash[i]) {
                redraw[i] = read[i] = false;
                offset[i] = cache_.offset[j];
                end = std::max(end, offset[i] + 4 * static_cast<std::size_t>(area_of(regions[i])));
            }
        any_redraw = any_redraw || redraw[i];
    }
    for (std::size_t i = 0; i < n; ++i)
        if (read[i]) {
            offset[i] = end;
            end += 4 * static_cast<std::size_t>(area_of(regions[i]));
        }
    if (end > staging_.size()) {
        end = 0;
        for (std::size_t i = 0; i < n; ++i) {
            read[i] = true;
            offset[i] = end;
            end += 4 * static_cast<std::size_t>(area_of(regions[i]));
        }
    }
    cache_.count = 0;  // until this frame's pixels are all in place
    if (any_redraw) draw_dirty(scene, redraw);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    for (std::size_t i = 0; i < n; ++i)
        if (read[i]) {
            const hal::Rect& r = regions[i];
            glReadPixels(r.x, r.y, r.width, r.height, GL_RGBA, GL_UNSIGNED_BYTE,
                         &staging_[offset[i]]);
        }
    // Any GL error before compositing: the target stays untouched.
    if (gl_failed("render")) return false;
    // Straight alpha once per read, not once per composite: kept regions are ready.
    for (std::size_t i = 0; i < n; ++i)
        if (read[i])
            unpremultiply(&staging_[offset[i]], static_cast<std::size_t>(area_of(regions[i])));
    for (std::size_t i = 0; i < n; ++i) {
        const hal::Rect& r = regions[i];
        // Outside the layer's rects its pixels are transparent (hal/overlay.hpp).
        bool transparent = true;
        for (std::size_t k = 0; k < target.rect_count && k < target.rects.size(); ++k) {
            const hal::Rect& t = target.rects[k];
            if (r.x < t.x + t.width && t.x < r.x + r.width && r.y < t.y + t.height &&
                t.y < r.y + r.height)
                transparent = false;
        }
        composite_over(&staging_[offset[i]], r.width, r.height,
                       target.rgba + static_cast<std::ptrdiff_t>(r.y) * target.stride + 4 * r.x,
                       target.stride, transparent);
    }
    cache_.count = n;
    std::copy_n(regions.begin(), n, cache_.rects.begin());
    std::copy_n(batch_.region_hash.begin(), n, cache_.hash.begin());
    std::copy_n(offset.begin(), n, cache_.offset.begin());
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
    auto renderer = std::make_unique<GlesRenderer>(display, context, surface, options);
    // Released here: the first call makes it current on the thread that will use it
    // (the analysis thread); a context current on another thread is EGL_BAD_ACCESS.
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    return renderer;
}

}  // namespace endotower::gles
