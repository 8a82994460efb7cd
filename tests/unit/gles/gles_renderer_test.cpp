// GlesRenderer headless: scenes rendered over a known target and compared with a CPU
// reference pixel by pixel.
// Tolerance (docs/rendering.md): the framebuffer holds 8-bit premultiplied colour, so a
// composited channel may differ from the exact "over" by up to 1 + 128 / alpha_out
// (alpha_out 0..255); opaque items on pixel boundaries are exact.
#include "endotower/gles/gles_renderer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace endotower::gles {
namespace {

using hal::Rgba8;

constexpr int kW = 320, kH = 240;

struct Target {
    std::vector<std::uint8_t> px;
    hal::OverlayLayer layer;
    explicit Target(int pad = 8) {
        layer.width = kW;
        layer.height = kH;
        layer.stride = 4 * kW + pad;
        px.assign(static_cast<std::size_t>(layer.stride) * kH, 0);
        layer.rgba = px.data();
    }
    // A deterministic pattern with every alpha: transparent, partial and opaque; the
    // layer's rect says so (outside its rects a layer is transparent).
    void pattern() {
        std::uint32_t s = 12345;
        for (auto& b : px) {
            s = s * 1664525u + 1013904223u;
            b = static_cast<std::uint8_t>(s >> 24);
        }
        layer.rects[0] = {0, 0, kW, kH};
        layer.rect_count = 1;
    }
    const std::uint8_t* at(int x, int y) const {
        return &px[static_cast<std::size_t>(y) * layer.stride + 4 * static_cast<std::size_t>(x)];
    }
    void set(int x, int y, Rgba8 c) {
        std::uint8_t* p =
            &px[static_cast<std::size_t>(y) * layer.stride + 4 * static_cast<std::size_t>(x)];
        p[0] = c.r, p[1] = c.g, p[2] = c.b, p[3] = c.a;
    }
    Rgba8 get(int x, int y) const {
        const std::uint8_t* p = at(x, y);
        return {p[0], p[1], p[2], p[3]};
    }
};

// The exact straight-alpha "over" of `s` onto `d`.
void over(Rgba8 s, Rgba8 d, double out[4]) {
    const double sa = s.a / 255.0, da = d.a / 255.0, oa = sa + da * (1 - sa);
    const double sc[3] = {double(s.r), double(s.g), double(s.b)};
    const double dc[3] = {double(d.r), double(d.g), double(d.b)};
    for (int c = 0; c < 3; ++c) out[c] = oa > 0 ? (sc[c] * sa + dc[c] * da * (1 - sa)) / oa : 0;
    out[3] = oa * 255;
}

bool inside(const hal::DrawnRects& d, int x, int y) {
    for (std::size_t i = 0; i < d.count; ++i) {
        const hal::Rect& r = d.rects[i];
        if (x >= r.x && x < r.x + r.width && y >= r.y && y < r.y + r.height) return true;
    }
    return false;
}

class GlesRendererTest : public ::testing::Test {
protected:
    void SetUp() override {
        std::string error;
        renderer_ = create_gles_renderer(error);
        if (!renderer_) GTEST_SKIP() << "no EGL display / GLES2 context here: " << error;
        ASSERT_TRUE(renderer_->configure(kW, kH)) << renderer_->error();
    }
    // Renders `scene` over a copy of `before`, checks the rect contract, returns the result.
    Target render(const hal::OverlayScene& scene, const Target& before) {
        Target after = before;
        after.layer.rgba = after.px.data();
        drawn_ = {};
        EXPECT_TRUE(renderer_->render(scene, after.layer, drawn_)) << renderer_->error();
        EXPECT_LE(drawn_.count, drawn_.rects.size());
        for (std::size_t i = 0; i < drawn_.count; ++i)
            for (std::size_t j = i + 1; j < drawn_.count; ++j) {
                const hal::Rect &a = drawn_.rects[i], &b = drawn_.rects[j];
                EXPECT_FALSE(a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height &&
                             b.y < a.y + a.height)
                    << "rects " << i << " and " << j << " overlap";
            }
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x)
                if (!inside(drawn_, x, y))
                    for (int c = 0; c < 4; ++c)
                        if (after.at(x, y)[c] != before.at(x, y)[c]) {
                            ADD_FAILURE()
                                << "pixel (" << x << ", " << y << ") changed outside the rects";
                            return after;
                        }
        // Row padding is never written.
        for (int y = 0; y < kH; ++y)
            for (int b = 4 * kW; b < before.layer.stride; ++b)
                EXPECT_EQ(after.px[static_cast<std::size_t>(y) * before.layer.stride + b],
                          before.px[static_cast<std::size_t>(y) * before.layer.stride + b]);
        return after;
    }
    std::unique_ptr<hal::OverlayRenderer> renderer_;
    hal::DrawnRects drawn_;
};

TEST_F(GlesRendererTest, EmptySceneTouchesNothing) {
    Target t;
    t.pattern();
    hal::OverlayScene scene;
    const Target after = render(scene, t);
    EXPECT_EQ(drawn_.count, 0u);
    EXPECT_EQ(after.px, t.px);
}

TEST_F(GlesRendererTest, OpaqueQuadIsExactAndOnlyIt) {
    Target t;
    t.pattern();
    hal::OverlayScene scene;
    scene.quads.add({.x = 40, .y = 30, .width = 100, .height = 50, .fill = {200, 100, 50, 255}});
    const Target after = render(scene, t);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const bool in = x >= 40 && x < 140 && y >= 30 && y < 80;
            if (in)
                ASSERT_EQ(after.get(x, y), (Rgba8{200, 100, 50, 255})) << x << ", " << y;
            else
                ASSERT_EQ(after.get(x, y), t.get(x, y)) << x << ", " << y;
        }
    ASSERT_EQ(drawn_.count, 1u);
    EXPECT_EQ(drawn_.rects[0], (hal::Rect{39, 29, 102, 52}));  // the 1-pixel antialiasing margin
}

TEST_F(GlesRendererTest, TranslucentQuadComposesOverWithinTolerance) {
    Target t;
    t.pattern();
    hal::OverlayScene scene;
    const Rgba8 fill{30, 200, 120, 128};
    scene.quads.add({.x = 10, .y = 10, .width = 200, .height = 150, .fill = fill});
    const Target after = render(scene, t);
    double worst = 0;
    for (int y = 10; y < 160; ++y)
        for (int x = 10; x < 210; ++x) {
            double ref[4];
            over(fill, t.get(x, y), ref);
            const double tol = 1 + 128.0 / ref[3];
            for (int c = 0; c < 4; ++c) {
                const double err = std::abs(after.at(x, y)[c] - ref[c]);
                worst = std::max(worst, err / tol);
                ASSERT_LE(err, tol) << "channel " << c << " at (" << x << ", " << y << ")";
            }
        }
    EXPECT_LE(worst, 1.0);
}

// Outside the layer's rects the target is transparent: the overlay is written as it
// is where it shows, and the colour bytes of transparent pixels elsewhere stay.
TEST_F(GlesRendererTest, TransparentLayerTakesTheOverlayAsIs) {
    Target t;
    t.pattern();
    t.layer.rect_count = 0;
    for (std::size_t y = 0; y < kH; ++y)
        for (std::size_t x = 0; x < kW; ++x) t.px[y * t.layer.stride + 4 * x + 3] = 0;
    hal::OverlayScene scene;
    const Rgba8 fill{30, 200, 120, 128};
    scene.quads.add({.x = 10, .y = 10, .width = 50, .height = 40, .fill = fill});
    const Target after = render(scene, t);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            if (x >= 10 && x < 60 && y >= 10 && y < 50) {
                const Rgba8 c = after.get(x, y);
                ASSERT_EQ(c.a, 128);
                ASSERT_NEAR(c.r, 30, 2);  // 1 + 128 / 128
                ASSERT_NEAR(c.g, 200, 2);
                ASSERT_NEAR(c.b, 120, 2);
            } else {
                ASSERT_EQ(after.get(x, y), t.get(x, y)) << x << ", " << y;
            }
        }
}

TEST_F(GlesRendererTest, RoundedCornersAndBorder) {
    Target t;  // transparent
    hal::OverlayScene scene;
    const Rgba8 fill{0, 0, 255, 255}, border{255, 255, 0, 255};
    scene.quads.add({.x = 20,
                     .y = 20,
                     .width = 100,
                     .height = 60,
                     .corner_px = 15,
                     .border_px = 4,
                     .fill = fill,
                     .border = border});
    const Target after = render(scene, t);
    EXPECT_EQ(after.get(70, 50), fill);    // the middle
    EXPECT_EQ(after.get(70, 21), border);  // inside the 4-pixel top border
    EXPECT_EQ(after.get(21, 50), border);
    EXPECT_EQ(after.get(70, 25), fill);       // just below it
    EXPECT_EQ(after.get(20, 20), (Rgba8{}));  // cut off by the 15-pixel corner
    EXPECT_EQ(after.get(23, 23), (Rgba8{}));
    EXPECT_EQ(after.get(119, 79), (Rgba8{}));
}

TEST_F(GlesRendererTest, SectorsDiscsAndArcs) {
    Target t;
    hal::OverlayScene scene;
    const Rgba8 red{255, 0, 0, 255}, green{0, 255, 0, 255};
    // A ring-menu item from 0 deg (+x) clockwise to 90 deg (+y, down on screen).
    scene.sectors.add({.cx = 80,
                       .cy = 80,
                       .r_inner = 30,
                       .r_outer = 60,
                       .start_deg = 0,
                       .end_deg = 90,
                       .fill = red});
    // A dwell-progress arc of a quarter: 12 o'clock clockwise to 3 o'clock.
    scene.discs.add(
        {.cx = 240, .cy = 120, .r_inner = 20, .r_outer = 40, .sweep_deg = 90, .colour = green});
    const Target after = render(scene, t);
    const float d45 = 45 * 3.14159265f / 180;
    EXPECT_EQ(after.get(80 + int(45 * std::cos(d45)), 80 + int(45 * std::sin(d45))), red);
    EXPECT_EQ(after.get(80 + 45, 80 - 10), (Rgba8{}));    // before 0 deg (above the +x axis)
    EXPECT_EQ(after.get(80 - 10, 80 + 45), (Rgba8{}));    // past 90 deg
    EXPECT_EQ(after.get(80 + 10, 80 + 10), (Rgba8{}));    // inside r_inner
    EXPECT_EQ(after.get(240 + 21, 120 - 21), green);      // 1:30
    EXPECT_EQ(after.get(240 - 21, 120 + 21), (Rgba8{}));  // 7:30, not swept yet
    EXPECT_EQ(after.get(240, 120), (Rgba8{}));            // the hole
}

TEST_F(GlesRendererTest, PolylineCoversItsWidth) {
    Target t;
    hal::OverlayScene scene;
    hal::SceneLine line;
    line.points[0] = {20, 100};
    line.points[1] = {200, 100};
    line.count = 2;
    line.width_px = 4;
    line.colour = {255, 255, 255, 255};
    scene.lines.add(line);
    const Target after = render(scene, t);
    for (int x = 22; x < 198; ++x) {
        for (int y = 98; y < 102; ++y) ASSERT_EQ(after.get(x, y), line.colour) << x << ", " << y;
        ASSERT_EQ(after.get(x, 96), (Rgba8{}));
        ASSERT_EQ(after.get(x, 103), (Rgba8{}));
    }
}

TEST_F(GlesRendererTest, TextDrawsGlyphsInsideItsBox) {
    Target t;
    hal::OverlayScene scene;
    hal::SceneText text;
    std::snprintf(text.utf8.data(), text.utf8.size(), "Patient Müller");
    text.x = 30, text.y = 40, text.size_px = 24;
    text.colour = {255, 255, 255, 255};
    scene.texts.add(text);
    const Target after = render(scene, t);
    int inked = 0, x_min = kW, x_max = -1, y_min = kH, y_max = -1;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            if (after.get(x, y).a > 0) {
                ++inked;
                x_min = std::min(x_min, x), x_max = std::max(x_max, x);
                y_min = std::min(y_min, y), y_max = std::max(y_max, y);
                EXPECT_EQ(after.get(x, y).r, 255);  // white text: only the coverage varies
            }
    EXPECT_GT(inked, 300);  // 13 glyphs of about 10 x 17 pixels, some of it ink
    EXPECT_GE(x_min, 30);
    EXPECT_LE(x_min, 33);
    EXPECT_GT(x_max, 30 + 13 * 8);  // about 13 advances of 8..15 pixels
    EXPECT_LT(x_max, 30 + 14 * 15);
    EXPECT_GE(y_min, 40);  // the line box is [40, 64)
    EXPECT_LE(y_max, 64);
    EXPECT_LE(y_min, 45);  // the capitals reach near the top of it
    // Centred text sits around its anchor.
    hal::OverlayScene centred;
    text.align = hal::SceneText::Align::kCentre;
    text.x = 160, text.y = 160;
    centred.texts.add(text);
    const Target c = render(centred, t);
    int left = 0, right = 0;
    for (int y = 148; y < 172; ++y)
        for (int x = 0; x < kW; ++x)
            if (c.get(x, y).a > 0) (x < 160 ? left : right) += 1;
    EXPECT_GT(left, 50);
    EXPECT_GT(right, 50);
    EXPECT_LT(std::abs(left - right), (left + right) / 3);
}

TEST_F(GlesRendererTest, ImageIsScaledIntoItsRectangle) {
    // 2 x 2 texels scaled to 20 x 20: pixels near the corners sample one texel only.
    const std::uint8_t px[16] = {255, 0, 0,   255, 0,   255, 0,   255,
                                 0,   0, 255, 255, 255, 255, 255, 255};
    ASSERT_TRUE(renderer_->set_image(3, {2, 2, 8, px})) << renderer_->error();
    Target t;
    t.pattern();
    hal::OverlayScene scene;
    scene.images.add({.image_id = 3, .x = 100, .y = 50, .width = 20, .height = 20});
    scene.images.add({.image_id = 5, .x = 0, .y = 0, .width = 20, .height = 20});  // never set
    const Target after = render(scene, t);
    EXPECT_EQ(after.get(101, 51), (Rgba8{255, 0, 0, 255}));
    EXPECT_EQ(after.get(118, 51), (Rgba8{0, 255, 0, 255}));
    EXPECT_EQ(after.get(101, 68), (Rgba8{0, 0, 255, 255}));
    EXPECT_EQ(after.get(118, 68), (Rgba8{255, 255, 255, 255}));
    EXPECT_EQ(after.get(5, 5), t.get(5, 5));
    EXPECT_FALSE(renderer_->set_image(8, {2, 2, 8, px}));
    EXPECT_NE(renderer_->error().find("id 8"), std::string::npos) << renderer_->error();
}

// A cube corner drawn by GL lands within 1 px of the same corner projected by OpenCV.
TEST_F(GlesRendererTest, CubeMatchesThePinholeWithinOnePixel) {
    Target t;
    hal::OverlayScene scene;
    scene.camera = {.fx = 300, .fy = 310, .cx = 157.3, .cy = 121.8, .near_mm = 5, .far_mm = 500};
    // Rotated 30 deg about y and 20 deg about x, centre at (10, -5, 120) mm.
    const cv::Vec3d rvec(20 * CV_PI / 180, 30 * CV_PI / 180, 0), tvec(10, -5, 120);
    cv::Matx33d r;
    cv::Rodrigues(rvec, r);
    hal::SceneBox box;
    box.size_mm = 40;
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
            box.camera_from_model[4 * static_cast<std::size_t>(c) + static_cast<std::size_t>(k)] =
                float(r(k, c));
    box.camera_from_model[12] = 10, box.camera_from_model[13] = -5, box.camera_from_model[14] = 120;
    box.camera_from_model[15] = 1;
    box.faces.fill({200, 60, 60, 255});
    scene.boxes.add(box);
    const Target after = render(scene, t);

    std::vector<cv::Point3d> corners;
    for (int k = 0; k < 8; ++k)
        corners.emplace_back(k & 1 ? 20 : -20, k & 2 ? 20 : -20, k & 4 ? 20 : -20);
    std::vector<cv::Point2d> uv;
    const cv::Matx33d K(300, 0, 157.3, 0, 310, 121.8, 0, 0, 1);
    cv::projectPoints(corners, rvec, tvec, K, cv::noArray(), uv);
    double u_min = 1e9, u_max = -1e9, v_min = 1e9, v_max = -1e9;
    for (const auto& p : uv)
        u_min = std::min(u_min, p.x), u_max = std::max(u_max, p.x), v_min = std::min(v_min, p.y),
        v_max = std::max(v_max, p.y);
    int x_min = kW, x_max = -1, y_min = kH, y_max = -1;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            if (after.get(x, y).a == 255)
                x_min = std::min(x_min, x), x_max = std::max(x_max, x), y_min = std::min(y_min, y),
                y_max = std::max(y_max, y);
    // The extreme corners of the silhouette: pixel centres are integers for OpenCV.
    EXPECT_NEAR(x_min, u_min, 1.0);
    EXPECT_NEAR(x_max, u_max, 1.0);
    EXPECT_NEAR(y_min, v_min, 1.0);
    EXPECT_NEAR(y_max, v_max, 1.0);
    // Shaded by the headlight: never brighter than the face colour, never black.
    const Rgba8 centre =
        after.get(int(std::lround((u_min + u_max) / 2)), int(std::lround((v_min + v_max) / 2)));
    EXPECT_EQ(centre.a, 255);
    EXPECT_LE(centre.r, 200);
    EXPECT_GE(centre.r, 70);
}

TEST_F(GlesRendererTest, NearerBoxHidesFartherOneWhateverTheOrder) {
    Target t;
    hal::OverlayScene scene;
    scene.camera = {.fx = 300, .fy = 300, .cx = 159.5, .cy = 119.5};
    auto box_at = [](float z, Rgba8 colour) {
        hal::SceneBox b;
        b.camera_from_model = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, z, 1};
        b.size_mm = 20;
        b.faces.fill(colour);
        return b;
    };
    scene.boxes.add(box_at(100, {255, 0, 0, 255}));
    scene.boxes.add(box_at(200, {0, 255, 0, 255}));  // drawn later, farther
    const Target after = render(scene, t);
    const Rgba8 c = after.get(160, 120);
    EXPECT_GT(c.r, 200);  // the near red face, head-on: fully lit
    EXPECT_EQ(c.g, 0);
}

TEST_F(GlesRendererTest, Line3IsProjectedAndCutAtTheNearPlane) {
    Target t;
    hal::OverlayScene scene;
    scene.camera = {.fx = 300, .fy = 300, .cx = 159.5, .cy = 119.5, .near_mm = 10};
    hal::SceneLine3 l;
    l.points[0] = {-20, 0, 100};
    l.points[1] = {20, 0, 100};
    l.points[2] = {20, 0, -50};  // behind the camera: cut at z = 10
    l.count = 3;
    l.width_px = 3;
    l.colour = {0, 0, 255, 255};
    scene.lines3.add(l);
    const Target after = render(scene, t);
    // (+-20, 0, 100) -> u = 159.5 -+ 60, v = 119.5: pixel row 119 and 120 straddle it.
    for (int x = 103; x < 217; ++x) ASSERT_EQ(after.get(x, 119).b, 255) << x;
    EXPECT_EQ(after.get(160, 110).a, 0);
}

TEST_F(GlesRendererTest, FullMenuRectsCoverEveryChangedPixel) {
    Target t;
    t.pattern();
    hal::OverlayScene scene;
    scene.camera = {.fx = 300, .fy = 300, .cx = 159.5, .cy = 119.5};
    for (int i = 0; i < 12; ++i) {
        const int row = i / 4, col = i % 4;  // a 4-column grid
        const float x = 5 + float(col) * 78, y = 5 + float(row) * 40;
        scene.quads.add({.x = x,
                         .y = y,
                         .width = 70,
                         .height = 32,
                         .corner_px = 6,
                         .border_px = 2,
                         .fill = {40, 40, 40, 160},
                         .border = {255, 255, 255, 220}});
        hal::SceneText text;
        std::snprintf(text.utf8.data(), text.utf8.size(), "Item %d", i);
        text.x = x + 35, text.y = y + 16, text.size_px = 18;
        text.align = hal::SceneText::Align::kCentre;
        text.colour = {255, 255, 255, 255};
        scene.texts.add(text);
    }
    for (int i = 0; i < 6; ++i)
        scene.sectors.add({.cx = 240,
                           .cy = 180,
                           .r_inner = 25,
                           .r_outer = 55,
                           .start_deg = float(i * 60),
                           .end_deg = float(i * 60 + 55),
                           .border_px = 1,
                           .fill = {0, 120, 255, 150},
                           .border = {255, 255, 255, 255}});
    scene.discs.add({.cx = 100, .cy = 200, .r_outer = 6, .colour = {255, 255, 0, 255}});
    hal::SceneBox box;
    box.camera_from_model = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -40, 40, 150, 1};
    box.faces.fill({120, 200, 255, 200});
    scene.boxes.add(box);
    const Target after = render(scene, t);  // checks the rect contract
    EXPECT_GE(drawn_.count, 2u);
    std::size_t changed = 0;
    for (std::size_t i = 0; i < t.px.size(); ++i) changed += after.px[i] != t.px[i];
    EXPECT_GT(changed, 10000u);
}

// Regions unchanged since the last frame are reused; the result must equal a render
// from scratch, bit for bit, whatever changed in between.
TEST_F(GlesRendererTest, ReusedRegionsEqualAFreshRender) {
    std::string error;
    auto fresh = create_gles_renderer(error);
    ASSERT_TRUE(fresh && fresh->configure(kW, kH)) << error;
    const std::uint8_t px[16] = {255, 0, 0,   255, 0,   255, 0,   255,
                                 0,   0, 255, 255, 255, 255, 255, 128};
    const std::uint8_t px2[16] = {9, 9, 9, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128};
    ASSERT_TRUE(renderer_->set_image(0, {2, 2, 8, px}));
    ASSERT_TRUE(fresh->set_image(0, {2, 2, 8, px2}));
    hal::OverlayScene menu;
    menu.camera = {.fx = 300, .fy = 300, .cx = 159.5, .cy = 119.5};
    for (int i = 0; i < 6; ++i)
        menu.quads.add({.x = 10.f + 50 * i,
                        .y = 10,
                        .width = 40,
                        .height = 30,
                        .corner_px = 5,
                        .fill = {40, 80, 200, 150}});
    menu.images.add({.image_id = 0, .x = 200, .y = 150, .width = 60, .height = 60});
    hal::SceneBox box;
    box.camera_from_model = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -40, 30, 200, 1};
    box.faces.fill({200, 200, 40, 255});
    menu.boxes.add(box);
    Target t;
    t.pattern();
    hal::OverlayScene frame = menu;
    frame.discs.add({.cx = 100, .cy = 150, .r_outer = 8, .colour = {255, 255, 0, 255}});
    render(frame, t);
    // Next frame: the cursor moved, one button highlighted, the image replaced.
    frame = menu;
    frame.discs.add({.cx = 130, .cy = 160, .r_outer = 8, .colour = {255, 255, 0, 255}});
    frame.quads.items[2].fill = {255, 255, 255, 200};
    ASSERT_TRUE(renderer_->set_image(0, {2, 2, 8, px2}));
    const Target reused = render(frame, t);
    Target scratch = t;
    scratch.layer.rgba = scratch.px.data();
    hal::DrawnRects drawn;
    ASSERT_TRUE(fresh->render(frame, scratch.layer, drawn)) << fresh->error();
    EXPECT_EQ(reused.px, scratch.px);
    // And the same scene again: nothing to draw, same pixels.
    const Target again = render(frame, t);
    EXPECT_EQ(again.px, scratch.px);
}

// 48 separate buttons: the report merges them into the contract's 16 rects, which
// still cover every changed pixel (checked in render()).
TEST_F(GlesRendererTest, ManyItemsMergeIntoSixteenRects) {
    Target t;
    t.pattern();
    hal::OverlayScene scene;
    for (int i = 0; i < 48; ++i) {
        const int row = i / 8, col = i % 8;  // an 8-column grid
        ASSERT_TRUE(scene.quads.add({.x = 4.f + 40 * float(col),
                                     .y = 4.f + 40 * float(row),
                                     .width = 30,
                                     .height = 30,
                                     .fill = {200, 10, 10, 255}}));
    }
    EXPECT_FALSE(scene.quads.add({}));  // past capacity
    const Target after = render(scene, t);
    EXPECT_EQ(drawn_.count, 16u);
    for (int i = 0; i < 48; ++i)
        EXPECT_EQ(after.get(5 + 40 * (i % 8), 5 + 40 * (i / 8)), (Rgba8{200, 10, 10, 255})) << i;
}

TEST_F(GlesRendererTest, WrongTargetSizeIsRefusedUntouched) {
    Target t;
    t.layer.width = kW - 1;
    hal::OverlayScene scene;
    scene.quads.add({.x = 0, .y = 0, .width = 10, .height = 10, .fill = {1, 2, 3, 255}});
    hal::DrawnRects drawn;
    EXPECT_FALSE(renderer_->render(scene, t.layer, drawn));
    EXPECT_NE(renderer_->error().find("configured size"), std::string::npos) << renderer_->error();
    for (std::uint8_t v : t.px) ASSERT_EQ(v, 0);
}

TEST(GlesRendererFont, MissingFontIsNamed) {
    std::string error;
    auto r = create_gles_renderer(error, {.font_path = "/nonexistent/font.ttf"});
    if (!r) GTEST_SKIP() << "no EGL display / GLES2 context here: " << error;
    EXPECT_FALSE(r->configure(64, 48));
    EXPECT_NE(r->error().find("/nonexistent/font.ttf"), std::string::npos) << r->error();
}

// A warped image (an overlay anchored to tissue) under a known homography: its four
// corners land within 1 px of the homography-mapped corners in the read-back pixels,
// and the inside is perspective-correct (each quadrant where the homography puts it).
TEST_F(GlesRendererTest, WarpedImageFollowsTheHomographyWithinOnePixel) {
    // 64x64, quadrants red (top-left), green (top-right), blue (bottom-right), white.
    constexpr int kS = 64;
    const Rgba8 quadrant[4] = {
        {255, 0, 0, 255}, {0, 255, 0, 255}, {0, 0, 255, 255}, {255, 255, 255, 255}};
    auto quadrant_of = [](double u, double v) {
        return u < 0.5 ? (v < 0.5 ? 0 : 3) : (v < 0.5 ? 1 : 2);
    };
    std::vector<std::uint8_t> px(4 * kS * kS);
    for (int y = 0; y < kS; ++y)
        for (int x = 0; x < kS; ++x) {
            const Rgba8 c = quadrant[quadrant_of((x + 0.5) / kS, (y + 0.5) / kS)];
            std::uint8_t* p =
                &px[4 * (static_cast<std::size_t>(y) * kS + static_cast<std::size_t>(x))];
            p[0] = c.r, p[1] = c.g, p[2] = c.b, p[3] = c.a;
        }
    ASSERT_TRUE(renderer_->set_image(2, {kS, kS, 4 * kS, px.data()})) << renderer_->error();
    // A strong perspective: the right edge is much shorter than the left.
    const cv::Point2f square[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const cv::Point2f quad[4] = {
        {40.3f, 30.7f}, {260.2f, 75.1f}, {250.6f, 160.4f}, {55.9f, 215.2f}};
    const cv::Matx33d h(cv::getPerspectiveTransform(square, quad));
    auto map = [&h](double u, double v) {
        const cv::Vec3d p = h * cv::Vec3d(u, v, 1);
        return cv::Point2d(p[0] / p[2], p[1] / p[2]);
    };
    Target t;
    hal::OverlayScene scene;
    hal::SceneImage im{.image_id = 2, .warped = true};
    for (int k = 0; k < 4; ++k) im.corners[static_cast<std::size_t>(k)] = {quad[k].x, quad[k].y};
    scene.images.add(im);
    const Target after = render(scene, t);

    // Each corner: the drawn pixel of its quadrant's colour farthest from the image's
    // centre (pixel centres at +0.5, edges at integers) lies within 1 px of the corner.
    const cv::Point2d centre = map(0.5, 0.5);
    for (int k = 0; k < 4; ++k) {
        double best = -1;
        cv::Point2d far;
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x)
                if (after.get(x, y) == quadrant[k]) {
                    const cv::Point2d c(x + 0.5, y + 0.5);
                    const double d = cv::norm(c - centre);
                    if (d > best) best = d, far = c;
                }
        ASSERT_GE(best, 0) << "corner " << k << " not drawn";
        EXPECT_LE(cv::norm(far - cv::Point2d(quad[k])), 1.0) << "corner " << k << " at " << far;
    }
    // Inside: a grid of image points, away from the quadrant borders, each drawn in its
    // quadrant's colour where the homography maps it. An affine (non-perspective) fill
    // puts the borders far off here (the image's centre by 52 px).
    int checked = 0;
    for (double u = 0.05; u < 1; u += 0.1)
        for (double v = 0.05; v < 1; v += 0.1) {
            const cv::Point2d p = map(u, v);
            const Rgba8 c = after.get(static_cast<int>(p.x), static_cast<int>(p.y));
            EXPECT_EQ(c, quadrant[quadrant_of(u, v)]) << "image point (" << u << ", " << v << ")";
            ++checked;
        }
    EXPECT_EQ(checked, 100);
    // Outside the quad nothing is drawn.
    EXPECT_EQ(after.get(20, 20).a, 0);
    EXPECT_EQ(after.get(300, 230).a, 0);
    // A non-convex quad is refused (not drawn at all).
    hal::OverlayScene bow;
    im.corners = {{{40, 30}, {260, 200}, {260, 30}, {40, 200}}};
    bow.images.add(im);
    const Target none = render(bow, t);
    EXPECT_EQ(none.px, t.px);
}

}  // namespace
}  // namespace endotower::gles
