#include "endotower/sim/compositor.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace endotower::sim {

namespace {

using hal::FrameFormat;
using hal::OverlayLayer;
using hal::PixelFormat;
using hal::Rect;

// out = (a*o + (255-a)*v + 127) / 255 for the three colour channels of one pixel at
// once, in 16-bit lanes of a 64-bit word (SWAR): each lane's a*o + (255-a)*v <= 65025
// fits, so nothing carries into the next lane, and the division-free
// (x + 128 + ((x + 128) >> 8)) >> 8, equal to (x + 127) / 255 for every such x
// (the unit tests check all a, o, v), stays within 16 bits too.
inline void mix_pixel(std::uint32_t a, const std::uint8_t* o, std::uint8_t* d) {
    constexpr std::uint64_t kLow = 0x00FF00FF00FFull;
    // Lane 0 = B, 1 = G, 2 = R: the overlay's bytes are R G B, the video's B G R.
    const std::uint64_t ol =
        std::uint64_t{o[2]} | std::uint64_t{o[1]} << 16 | std::uint64_t{o[0]} << 32;
    const std::uint64_t vl =
        std::uint64_t{d[0]} | std::uint64_t{d[1]} << 16 | std::uint64_t{d[2]} << 32;
    std::uint64_t x = ol * a + vl * (255u - a) + 0x008000800080ull;
    x = ((x + ((x >> 8) & kLow)) >> 8) & kLow;
    d[0] = static_cast<std::uint8_t>(x);
    d[1] = static_cast<std::uint8_t>(x >> 16);
    d[2] = static_cast<std::uint8_t>(x >> 32);
}

inline std::uint64_t load64(const std::uint8_t* p) {
    std::uint64_t w;
    std::memcpy(&w, p, sizeof w);
    return w;
}

// Blends one run of `n` overlay pixels (R G B A) into video pixels (B G R [X]).
// Overlays are mostly fully transparent or fully opaque (text, outlines), so four
// pixels at a time are tested for those two cases before doing any arithmetic.
template <int kBpp>
void blend_run(std::uint8_t* dst, const std::uint8_t* ov, int n) {
    // Byte 3 of each of the two pixels in a 64-bit load.
    constexpr std::uint64_t kAlpha =
        std::endian::native == std::endian::little ? 0xFF000000FF000000ull : 0x000000FF000000FFull;
    int i = 0;
    for (; i + 4 <= n; i += 4, ov += 16, dst += 4 * kBpp) {
        const std::uint64_t w0 = load64(ov);
        const std::uint64_t w1 = load64(ov + 8);
        if (((w0 | w1) & kAlpha) == 0) continue;  // all transparent: video stays
        if ((w0 & w1 & kAlpha) == kAlpha) {       // all opaque: plain store
            for (int k = 0; k < 4; ++k) {
                dst[k * kBpp + 0] = ov[k * 4 + 2];
                dst[k * kBpp + 1] = ov[k * 4 + 1];
                dst[k * kBpp + 2] = ov[k * 4 + 0];
            }
            continue;
        }
        for (int k = 0; k < 4; ++k) {
            mix_pixel(ov[k * 4 + 3], ov + k * 4, dst + k * kBpp);
        }
    }
    for (; i < n; ++i, ov += 4, dst += kBpp) {
        const std::uint32_t a = ov[3];
        if (a == 0) continue;
        mix_pixel(a, ov, dst);
    }
}

struct Span {
    int x0, x1;  // [x0, x1)
};

// Blends every pixel covered by at least one rectangle exactly once: overlapping
// rectangles must not blend a pixel twice in place.
template <int kBpp>
void blend_rects(int width, int height, int stride, std::uint8_t* pixels,
                 const OverlayLayer& overlay) {
    Rect clipped[OverlayLayer::kMaxRects];
    int count = 0;
    int y_begin = height, y_end = 0;
    const std::size_t n = std::min(overlay.rect_count, OverlayLayer::kMaxRects);
    for (std::size_t i = 0; i < n; ++i) {
        const Rect& r = overlay.rects[i];
        if (r.empty()) continue;
        // 64-bit so that huge rectangles cannot overflow x + width.
        const long long x0 = std::max<long long>(r.x, 0);
        const long long y0 = std::max<long long>(r.y, 0);
        const long long x1 = std::min<long long>(static_cast<long long>(r.x) + r.width, width);
        const long long y1 = std::min<long long>(static_cast<long long>(r.y) + r.height, height);
        if (x0 >= x1 || y0 >= y1) continue;
        clipped[count++] = Rect{static_cast<int>(x0), static_cast<int>(y0),
                                static_cast<int>(x1 - x0), static_cast<int>(y1 - y0)};
        y_begin = std::min(y_begin, static_cast<int>(y0));
        y_end = std::max(y_end, static_cast<int>(y1));
    }
    if (count == 0) return;

    // One rectangle (the common case): no span bookkeeping.
    if (count == 1) {
        const Rect& r = clipped[0];
        for (int y = r.y; y < r.y + r.height; ++y)
            blend_run<kBpp>(pixels + static_cast<std::size_t>(y) * stride +
                                static_cast<std::size_t>(r.x) * kBpp,
                            overlay.rgba + static_cast<std::size_t>(y) * overlay.stride +
                                static_cast<std::size_t>(r.x) * 4,
                            r.width);
        return;
    }

    Span spans[OverlayLayer::kMaxRects];
    for (int y = y_begin; y < y_end; ++y) {
        // The rectangles crossing this row, sorted by x (insertion sort: at most 32).
        int k = 0;
        for (int i = 0; i < count; ++i) {
            const Rect& r = clipped[i];
            if (y < r.y || y >= r.y + r.height) continue;
            int j = k++;
            while (j > 0 && spans[j - 1].x0 > r.x) {
                spans[j] = spans[j - 1];
                --j;
            }
            spans[j] = Span{r.x, r.x + r.width};
        }
        std::uint8_t* row = pixels + static_cast<std::size_t>(y) * stride;
        const std::uint8_t* orow = overlay.rgba + static_cast<std::size_t>(y) * overlay.stride;
        int i = 0;
        while (i < k) {
            // Merge overlapping or touching spans into one run.
            Span s = spans[i++];
            while (i < k && spans[i].x0 <= s.x1) s.x1 = std::max(s.x1, spans[i++].x1);
            blend_run<kBpp>(row + static_cast<std::size_t>(s.x0) * kBpp,
                            orow + static_cast<std::size_t>(s.x0) * 4, s.x1 - s.x0);
        }
    }
}

bool blendable(const FrameFormat& f) {
    return f.valid() &&
           (f.pixel_format == PixelFormat::kBgr24 || f.pixel_format == PixelFormat::kBgra32);
}

bool overlay_fits(const FrameFormat& f, const OverlayLayer& overlay) {
    return overlay.width == f.width && overlay.height == f.height && overlay.rgba != nullptr &&
           overlay.stride >= 4 * overlay.width;
}

}  // namespace

bool blend_in_place(const FrameFormat& format, std::uint8_t* pixels, const OverlayLayer& overlay) {
    if (!blendable(format) || pixels == nullptr) return false;
    if (overlay.empty()) return true;
    if (!overlay_fits(format, overlay)) return false;
    if (format.pixel_format == PixelFormat::kBgr24)
        blend_rects<3>(format.width, format.height, format.stride, pixels, overlay);
    else
        blend_rects<4>(format.width, format.height, format.stride, pixels, overlay);
    return true;
}

bool compose(const hal::Frame& video, const OverlayLayer* overlay, std::uint8_t* out,
             int out_stride) {
    const FrameFormat& f = video.format;
    if (!blendable(f) || video.data == nullptr || out == nullptr) return false;
    const std::size_t row_bytes = static_cast<std::size_t>(f.width) *
                                  static_cast<std::size_t>(hal::bytes_per_pixel(f.pixel_format));
    if (out_stride < 0 || static_cast<std::size_t>(out_stride) < row_bytes) return false;
    if (overlay != nullptr && !overlay->empty() && !overlay_fits(f, *overlay)) return false;

    // Copy first, then blend the copy in place: the copy is a plain memcpy (the
    // bulk of the work), and blending reads the same bytes the video holds.
    if (out_stride == f.stride) {
        // One copy for the whole image; the last row's padding is not copied.
        std::memcpy(out, video.data,
                    static_cast<std::size_t>(f.stride) * static_cast<std::size_t>(f.height - 1) +
                        row_bytes);
    } else {
        for (int y = 0; y < f.height; ++y)
            std::memcpy(out + static_cast<std::size_t>(y) * out_stride,
                        video.data + static_cast<std::size_t>(y) * f.stride, row_bytes);
    }
    if (overlay == nullptr || overlay->empty()) return true;
    FrameFormat out_format = f;
    out_format.stride = out_stride;
    return blend_in_place(out_format, out, *overlay);
}

}  // namespace endotower::sim
