// GlesOverlay on a headless EGL context (surfaceless platform, Mesa llvmpipe): a known
// layer is drawn into an FBO and read back, pixel by pixel.
#include "endotower/display/gles_overlay.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES2/gl2.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <vector>

namespace endotower::display {
namespace {

// A GLES2 context without a window, drawing into a width x height RGBA texture.
class Headless {
public:
    bool open(int w, int h) {
        auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
            eglGetProcAddress("eglGetPlatformDisplayEXT"));
        if (get_display == nullptr) return false;
        display_ = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (display_ == EGL_NO_DISPLAY || !eglInitialize(display_, nullptr, nullptr)) return false;
        eglBindAPI(EGL_OPENGL_ES_API);
        const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES2_BIT, EGL_SURFACE_TYPE,
                                  EGL_PBUFFER_BIT, EGL_NONE};
        EGLConfig config = nullptr;
        EGLint n = 0;
        if (!eglChooseConfig(display_, attribs, &config, 1, &n) || n == 0) return false;
        const EGLint ctx[] = {EGL_CONTEXT_CLIENT_VERSION, 2, EGL_NONE};
        context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, ctx);
        if (context_ == EGL_NO_CONTEXT ||
            !eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
            return false;
        w_ = w;
        h_ = h;
        glGenTextures(1, &tex_);
        glBindTexture(GL_TEXTURE_2D, tex_);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        glGenFramebuffers(1, &fbo_);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex_, 0);
        return glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    }
    ~Headless() {
        if (context_ != EGL_NO_CONTEXT) {
            glDeleteFramebuffers(1, &fbo_);
            glDeleteTextures(1, &tex_);
            eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            eglDestroyContext(display_, context_);
        }
        if (display_ != EGL_NO_DISPLAY) eglTerminate(display_);
    }
    // The framebuffer, memory row 0 first, RGBA.
    std::vector<std::uint8_t> read() {
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
        std::vector<std::uint8_t> px(static_cast<std::size_t>(w_) * h_ * 4);
        glReadPixels(0, 0, w_, h_, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
        return px;
    }

private:
    EGLDisplay display_ = EGL_NO_DISPLAY;
    EGLContext context_ = EGL_NO_CONTEXT;
    unsigned tex_ = 0, fbo_ = 0;
    int w_ = 0, h_ = 0;
};

// An overlay layer with its own pixels.
struct Layer {
    std::vector<std::uint8_t> px;
    hal::OverlayLayer layer;
    Layer(int w, int h, int pad = 0) {
        layer.width = w;
        layer.height = h;
        layer.stride = 4 * w + pad;
        px.assign(static_cast<std::size_t>(layer.stride) * h, 0);
        layer.rgba = px.data();
    }
    void fill(hal::Rect r, std::uint8_t R, std::uint8_t G, std::uint8_t B, std::uint8_t A,
              bool mark = true) {
        for (int y = r.y; y < r.y + r.height; ++y)
            for (int x = r.x; x < r.x + r.width; ++x) {
                std::uint8_t* p = &px[static_cast<std::size_t>(y) * layer.stride + 4 * x];
                p[0] = R, p[1] = G, p[2] = B, p[3] = A;
            }
        if (mark) layer.rects[layer.rect_count++] = r;
    }
};

constexpr int kW = 64, kH = 48;

class GlesOverlayTest : public ::testing::Test {
protected:
    void SetUp() override {
        // Mesa's software rasteriser: no GPU or display needed.
        setenv("EGL_PLATFORM", "surfaceless", 0);
        if (!gl_.open(kW, kH))
            GTEST_SKIP()
                << "no EGL surfaceless GLES2 context on this host (Mesa's libegl-mesa0 missing?)";
        ASSERT_TRUE(overlay_.init(kW, kH, false)) << overlay_.error();
    }
    static const std::uint8_t* at(const std::vector<std::uint8_t>& px, int x, int y) {
        return &px[(static_cast<std::size_t>(y) * kW + x) * 4];
    }
    Headless gl_;
    GlesOverlay overlay_;
};

TEST_F(GlesOverlayTest, NothingDrawnIsFullyTransparent) {
    ASSERT_TRUE(overlay_.draw(nullptr)) << overlay_.error();
    for (std::uint8_t v : gl_.read()) ASSERT_EQ(v, 0);
}

TEST_F(GlesOverlayTest, OpaqueRectsExactAndOnlyThem) {
    Layer l(kW, kH, 16);  // padded rows: the stride is honoured
    l.fill({10, 5, 20, 8}, 200, 100, 50, 255);
    l.fill({0, 40, 3, 8}, 1, 2, 3, 255);
    l.fill({40, 20, 10, 10}, 90, 91, 92, 255, false);  // outside every rect: never shown
    ASSERT_TRUE(overlay_.draw(&l.layer)) << overlay_.error();
    const auto px = gl_.read();
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const std::uint8_t* p = at(px, x, y);
            const bool in1 = x >= 10 && x < 30 && y >= 5 && y < 13, in2 = x < 3 && y >= 40;
            const int want[4] = {in1   ? 200
                                 : in2 ? 1
                                       : 0,
                                 in1   ? 100
                                 : in2 ? 2
                                       : 0,
                                 in1   ? 50
                                 : in2 ? 3
                                       : 0,
                                 in1 || in2 ? 255 : 0};
            for (int c = 0; c < 4; ++c)
                ASSERT_EQ(p[c], want[c]) << "pixel " << x << "," << y << " channel " << c;
        }
}

TEST_F(GlesOverlayTest, PremultipliesStraightAlpha) {
    Layer l(kW, kH);
    l.fill({0, 0, 4, 4}, 200, 100, 50, 128);
    l.fill({8, 0, 4, 4}, 255, 255, 255, 0);  // transparent white must not show
    ASSERT_TRUE(overlay_.draw(&l.layer)) << overlay_.error();
    const auto px = gl_.read();
    const std::uint8_t* p = at(px, 1, 1);
    // rgb * a / 255, rounded: 100.4, 50.2, 25.1; the GPU may round either way.
    EXPECT_NEAR(p[0], 100, 1);
    EXPECT_NEAR(p[1], 50, 1);
    EXPECT_NEAR(p[2], 25, 1);
    EXPECT_EQ(p[3], 128);
    for (int c = 0; c < 4; ++c) EXPECT_EQ(at(px, 9, 1)[c], 0);
}

TEST_F(GlesOverlayTest, PreviousFrameLeavesNothingBehind) {
    Layer a(kW, kH);
    a.fill({0, 0, 16, 16}, 255, 0, 0, 255);
    ASSERT_TRUE(overlay_.draw(&a.layer));
    Layer b(kW, kH);
    b.fill({32, 32, 8, 8}, 0, 255, 0, 255);
    ASSERT_TRUE(overlay_.draw(&b.layer));
    const auto px = gl_.read();
    EXPECT_EQ(at(px, 5, 5)[3], 0);
    EXPECT_EQ(at(px, 5, 5)[0], 0);
    EXPECT_EQ(at(px, 35, 35)[1], 255);
    EXPECT_EQ(at(px, 35, 35)[3], 255);
}

// With a known buffer age only what was drawn since is cleared: the rest of the
// buffer is left alone (here a marker that no draw made stays).
TEST_F(GlesOverlayTest, BufferAgeClearsOnlyWhatWasDrawnSince) {
    Layer a(kW, kH);
    a.fill({0, 0, 16, 16}, 255, 0, 0, 255);
    ASSERT_TRUE(overlay_.draw(&a.layer, 0));
    glEnable(GL_SCISSOR_TEST);
    glScissor(40, 40, 4, 4);
    glClearColor(0.f, 0.f, 1.f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_SCISSOR_TEST);
    Layer b(kW, kH);
    b.fill({20, 0, 8, 8}, 0, 255, 0, 255);
    ASSERT_TRUE(overlay_.draw(&b.layer, 1));
    auto px = gl_.read();
    EXPECT_EQ(at(px, 5, 5)[3], 0);      // a's rect: cleared
    EXPECT_EQ(at(px, 21, 1)[1], 255);   // b drawn
    EXPECT_EQ(at(px, 41, 41)[2], 255);  // the marker: untouched
    // Age 2: the buffer holds the draw before last; a's and b's rects are cleared.
    Layer c(kW, kH);
    c.fill({0, 30, 4, 4}, 9, 9, 9, 255);
    ASSERT_TRUE(overlay_.draw(&c.layer, 2));
    px = gl_.read();
    EXPECT_EQ(at(px, 21, 1)[3], 0);
    EXPECT_EQ(at(px, 1, 31)[0], 9);
    EXPECT_EQ(at(px, 41, 41)[2], 255);
    // Unknown age: everything cleared.
    ASSERT_TRUE(overlay_.draw(&c.layer, 0));
    px = gl_.read();
    EXPECT_EQ(at(px, 41, 41)[3], 0);
}

TEST_F(GlesOverlayTest, LargerLayerIsCutOff) {
    Layer l(kW + 20, kH + 10);
    l.fill({kW - 2, kH - 2, 10, 10}, 7, 8, 9, 255);
    ASSERT_TRUE(overlay_.draw(&l.layer)) << overlay_.error();
    const auto px = gl_.read();
    EXPECT_EQ(at(px, kW - 1, kH - 1)[0], 7);
    EXPECT_EQ(at(px, kW - 3, kH - 3)[3], 0);
}

// A window surface (the GBM scanout surface) has its top row at GL y = height - 1:
// flip_y puts layer row 0 there, and the scissored rects follow.
TEST_F(GlesOverlayTest, FlipForWindowSurfaces) {
    GlesOverlay flipped;
    ASSERT_TRUE(flipped.init(kW, kH, true)) << flipped.error();
    Layer l(kW, kH);
    l.fill({10, 5, 20, 8}, 200, 100, 50, 255);
    ASSERT_TRUE(flipped.draw(&l.layer)) << flipped.error();
    const auto px = gl_.read();
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const int layer_row = kH - 1 - y;
            const bool in = x >= 10 && x < 30 && layer_row >= 5 && layer_row < 13;
            ASSERT_EQ(at(px, x, y)[0], in ? 200 : 0) << x << "," << y;
            ASSERT_EQ(at(px, x, y)[3], in ? 255 : 0) << x << "," << y;
        }
}

}  // namespace
}  // namespace endotower::display
