#include "endotower/sim/compositor.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

namespace endotower::sim {
namespace {

using hal::Frame;
using hal::FrameFormat;
using hal::OverlayLayer;
using hal::PixelFormat;
using hal::Rect;

// The contract's formula, written the slow obvious way.
std::uint8_t over(int a, int o, int v) {
    return static_cast<std::uint8_t>((a * o + (255 - a) * v + 127) / 255);
}

struct Image {
    FrameFormat format;
    std::vector<std::uint8_t> bytes;
    Image(int w, int h, PixelFormat pf, int padding = 0)
        : format{w, h, w * hal::bytes_per_pixel(pf) + padding, pf}, bytes(format.size_bytes()) {}
    std::uint8_t* px(int x, int y) {
        return bytes.data() + static_cast<std::size_t>(y) * format.stride +
               static_cast<std::size_t>(x) * hal::bytes_per_pixel(format.pixel_format);
    }
    Frame frame() {
        Frame f;
        f.format = format;
        f.data = bytes.data();
        return f;
    }
};

struct Layer {
    OverlayLayer layer;
    std::vector<std::uint8_t> rgba;
    Layer(int w, int h, int padding = 0) : rgba(static_cast<std::size_t>(w * 4 + padding) * h) {
        layer.width = w;
        layer.height = h;
        layer.stride = w * 4 + padding;
        layer.rgba = rgba.data();
    }
    std::uint8_t* px(int x, int y) {
        return rgba.data() + static_cast<std::size_t>(y) * layer.stride +
               static_cast<std::size_t>(x) * 4;
    }
    void add(Rect r) { layer.rects[layer.rect_count++] = r; }
};

void fill_random(std::vector<std::uint8_t>& v, unsigned seed) {
    std::mt19937 rng(seed);
    for (auto& b : v) b = static_cast<std::uint8_t>(rng());
}

bool covered(const OverlayLayer& l, int x, int y) {
    for (std::size_t i = 0; i < l.rect_count; ++i) {
        const Rect& r = l.rects[i];
        if (x >= r.x && x < r.x + r.width && y >= r.y && y < r.y + r.height) return true;
    }
    return false;
}

// Reference composition of one video pixel (B G R [X]) under the overlay.
void expect_composed(Image& in, Image& out, Layer& ov) {
    const int bpp = hal::bytes_per_pixel(in.format.pixel_format);
    for (int y = 0; y < in.format.height; ++y) {
        for (int x = 0; x < in.format.width; ++x) {
            const std::uint8_t* v = in.px(x, y);
            const std::uint8_t* got = out.px(x, y);
            if (!covered(ov.layer, x, y)) {
                for (int c = 0; c < bpp; ++c)
                    ASSERT_EQ(got[c], v[c]) << "outside rects at " << x << "," << y;
                continue;
            }
            const std::uint8_t* o = ov.px(x, y);
            ASSERT_EQ(got[0], over(o[3], o[2], v[0])) << x << "," << y;
            ASSERT_EQ(got[1], over(o[3], o[1], v[1])) << x << "," << y;
            ASSERT_EQ(got[2], over(o[3], o[0], v[2])) << x << "," << y;
            if (bpp == 4) {
                ASSERT_EQ(got[3], v[3]) << "the X byte is the video's";
            }
        }
    }
}

TEST(Compositor, FormulaIsExactForEveryAlphaOverlayAndVideoValue) {
    // 256 x 256 pixels: video value = x, overlay value = y, one pass per alpha.
    Image img(256, 256, PixelFormat::kBgr24);
    Layer ov(256, 256);
    ov.add({0, 0, 256, 256});
    for (int a = 0; a < 256; ++a) {
        for (int y = 0; y < 256; ++y) {
            for (int x = 0; x < 256; ++x) {
                std::uint8_t* p = img.px(x, y);
                p[0] = p[1] = p[2] = static_cast<std::uint8_t>(x);
                std::uint8_t* o = ov.px(x, y);
                o[0] = o[1] = o[2] = static_cast<std::uint8_t>(y);
                o[3] = static_cast<std::uint8_t>(a);
            }
        }
        ASSERT_TRUE(blend_in_place(img.format, img.bytes.data(), ov.layer));
        int wrong = 0;
        for (int y = 0; y < 256; ++y) {
            for (int x = 0; x < 256; ++x) {
                const std::uint8_t want = over(a, y, x);
                const std::uint8_t* p = img.px(x, y);
                wrong += (p[0] != want) + (p[1] != want) + (p[2] != want);
            }
        }
        ASSERT_EQ(wrong, 0) << "alpha " << a;
    }
}

TEST(Compositor, OverlayRgbLandsOnVideoBgrAndOpaqueIsAPlainStore) {
    Image img(8, 2, PixelFormat::kBgr24);
    std::fill(img.bytes.begin(), img.bytes.end(), 200);
    Layer ov(8, 2);
    for (int x = 0; x < 8; ++x) {
        std::uint8_t* o = ov.px(x, 0);
        o[0] = 10, o[1] = 20, o[2] = 30, o[3] = 255;  // R G B A
    }
    ov.add({0, 0, 8, 2});
    ASSERT_TRUE(blend_in_place(img.format, img.bytes.data(), ov.layer));
    for (int x = 0; x < 8; ++x) {
        EXPECT_EQ(img.px(x, 0)[0], 30);                               // B
        EXPECT_EQ(img.px(x, 0)[1], 20);                               // G
        EXPECT_EQ(img.px(x, 0)[2], 10);                               // R
        for (int c = 0; c < 3; ++c) EXPECT_EQ(img.px(x, 1)[c], 200);  // alpha 0 row
    }
    // Half alpha: (128*o + 127*200 + 127) / 255.
    Image half(1, 1, PixelFormat::kBgr24);
    half.bytes = {200, 200, 200};
    Layer h(1, 1);
    h.rgba = {10, 20, 30, 128};
    h.layer.rgba = h.rgba.data();
    h.add({0, 0, 1, 1});
    ASSERT_TRUE(blend_in_place(half.format, half.bytes.data(), h.layer));
    EXPECT_EQ(half.bytes[0], (128 * 30 + 127 * 200 + 127) / 255);  // 115
    EXPECT_EQ(half.bytes[1], (128 * 20 + 127 * 200 + 127) / 255);  // 110
    EXPECT_EQ(half.bytes[2], (128 * 10 + 127 * 200 + 127) / 255);  // 105
    EXPECT_EQ(half.bytes[0], 115);
}

TEST(Compositor, ComposeCopiesBitExactOutsideRectsAndWhereAlphaIsZero) {
    Image in(97, 61, PixelFormat::kBgr24);
    fill_random(in.bytes, 1);
    Layer ov(97, 61);
    // Junk everywhere, also outside the rectangles: the compositor must not look there.
    fill_random(ov.rgba, 2);
    for (int y = 0; y < 61; ++y)
        for (int x = 0; x < 97; ++x)
            if ((x + y) % 3 == 0) ov.px(x, y)[3] = 0;  // transparent pixels inside rects
    ov.add({5, 7, 40, 20});
    ov.add({60, 30, 30, 25});
    Image out(97, 61, PixelFormat::kBgr24);
    const Frame f = in.frame();
    ASSERT_TRUE(compose(f, &ov.layer, out.bytes.data(), out.format.stride));
    expect_composed(in, out, ov);
    for (int y = 0; y < 61; ++y)
        for (int x = 0; x < 97; ++x)
            if ((x + y) % 3 == 0) {
                for (int c = 0; c < 3; ++c) ASSERT_EQ(out.px(x, y)[c], in.px(x, y)[c]);
            }
}

TEST(Compositor, RectsAreClippedToTheFrame) {
    Image in(50, 40, PixelFormat::kBgr24);
    fill_random(in.bytes, 3);
    Layer ov(50, 40);
    fill_random(ov.rgba, 4);
    ov.add({-10, -5, 20, 15});           // top-left corner, partly outside
    ov.add({45, 35, 100, 100});          // bottom-right, mostly outside
    ov.add({60, 0, 10, 10});             // entirely outside
    ov.add({0, -100, 3, 50});            // above, reaching in
    ov.add({2147483000, 0, 100000, 5});  // x + width would overflow int
    ov.add({10, 10, 0, 5});              // empty
    Image out(50, 40, PixelFormat::kBgr24);
    ASSERT_TRUE(compose(in.frame(), &ov.layer, out.bytes.data(), out.format.stride));
    // The reference clips implicitly by walking only the frame's pixels.
    ov.layer.rects[4] = Rect{};
    expect_composed(in, out, ov);
}

TEST(Compositor, OverlappingRectsBlendEachPixelOnce) {
    Image img(64, 48, PixelFormat::kBgr24);
    fill_random(img.bytes, 5);
    Image original = img;
    Layer ov(64, 48);
    fill_random(ov.rgba, 6);
    ov.add({0, 0, 40, 30});
    ov.add({20, 10, 40, 30});  // overlaps the first
    ov.add({10, 5, 5, 5});     // inside the first
    ov.add({39, 29, 2, 2});    // touching
    ASSERT_TRUE(blend_in_place(img.format, img.bytes.data(), ov.layer));
    expect_composed(original, img, ov);
}

TEST(Compositor, Bgra32KeepsTheFourthByteAndHonoursStrides) {
    Image in(33, 17, PixelFormat::kBgra32, 12);  // padded rows
    fill_random(in.bytes, 7);
    Layer ov(33, 17, 8);
    fill_random(ov.rgba, 8);
    ov.add({3, 2, 25, 11});
    Image out(33, 17, PixelFormat::kBgra32, 40);  // another stride
    std::fill(out.bytes.begin(), out.bytes.end(), 0xAB);
    ASSERT_TRUE(compose(in.frame(), &ov.layer, out.bytes.data(), out.format.stride));
    expect_composed(in, out, ov);
    // Row padding of the output is not written.
    for (int y = 0; y < 17; ++y)
        for (int b = 33 * 4; b < out.format.stride; ++b)
            ASSERT_EQ(out.bytes[static_cast<std::size_t>(y) * out.format.stride + b], 0xAB);
}

TEST(Compositor, NoOverlayOrNoRectsIsAPlainCopy) {
    Image in(31, 9, PixelFormat::kBgr24, 5);
    fill_random(in.bytes, 9);
    Image out(31, 9, PixelFormat::kBgr24, 5);
    ASSERT_TRUE(compose(in.frame(), nullptr, out.bytes.data(), out.format.stride));
    for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 31 * 3; ++x)
            ASSERT_EQ(out.bytes[y * out.format.stride + x], in.bytes[y * in.format.stride + x]);
    Layer empty(0, 0);  // no rects: its size does not matter
    Image out2(31, 9, PixelFormat::kBgr24);
    ASSERT_TRUE(compose(in.frame(), &empty.layer, out2.bytes.data(), out2.format.stride));
    for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 31; ++x)
            for (int c = 0; c < 3; ++c) ASSERT_EQ(out2.px(x, y)[c], in.px(x, y)[c]);
}

TEST(Compositor, RejectsMismatchedInputs) {
    Image in(16, 8, PixelFormat::kBgr24);
    Image out(16, 8, PixelFormat::kBgr24);
    Layer ov(15, 8);  // one pixel too narrow
    ov.add({0, 0, 4, 4});
    EXPECT_FALSE(compose(in.frame(), &ov.layer, out.bytes.data(), out.format.stride));
    EXPECT_FALSE(blend_in_place(in.format, in.bytes.data(), ov.layer));
    Layer good(16, 8);
    good.add({0, 0, 4, 4});
    EXPECT_FALSE(compose(in.frame(), &good.layer, out.bytes.data(), 16 * 3 - 1));  // short stride
    EXPECT_FALSE(compose(in.frame(), &good.layer, nullptr, out.format.stride));
    Image gray(16, 8, PixelFormat::kGray8);
    EXPECT_FALSE(compose(gray.frame(), &good.layer, out.bytes.data(), out.format.stride));
    EXPECT_FALSE(blend_in_place(gray.format, gray.bytes.data(), good.layer));
    Image yuyv(16, 8, PixelFormat::kYuyv);
    EXPECT_FALSE(blend_in_place(yuyv.format, yuyv.bytes.data(), good.layer));
    good.layer.rgba = nullptr;
    EXPECT_FALSE(blend_in_place(in.format, in.bytes.data(), good.layer));
}

TEST(Compositor, FullHdWithTenPercentOverlayMatchesTheReference) {
    // The benchmark's shape: 1920x1080 BGR24, an overlay over about a tenth of it
    // with transparent, opaque and partial pixels.
    Image in(1920, 1080, PixelFormat::kBgr24);
    fill_random(in.bytes, 10);
    Layer ov(1920, 1080);
    for (int y = 0; y < 1080; ++y) {
        for (int x = 0; x < 1920; ++x) {
            std::uint8_t* o = ov.px(x, y);
            o[0] = static_cast<std::uint8_t>(x);
            o[1] = static_cast<std::uint8_t>(y);
            o[2] = static_cast<std::uint8_t>(x ^ y);
            const int band = (x / 7 + y / 5) % 3;
            o[3] = band == 0 ? 0 : band == 1 ? 255 : static_cast<std::uint8_t>(x * 31 + y);
        }
    }
    ov.add({100, 100, 607, 342});
    Image out(1920, 1080, PixelFormat::kBgr24);
    ASSERT_TRUE(compose(in.frame(), &ov.layer, out.bytes.data(), out.format.stride));
    expect_composed(in, out, ov);
}

}  // namespace
}  // namespace endotower::sim
