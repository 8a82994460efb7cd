#include "composite.hpp"

#include <array>
#include <cstring>

namespace endotower::gles {

namespace {

// table[a][c] = round(c * 255 / a), saturated.
struct Unpremultiply {
    std::array<std::array<std::uint8_t, 256>, 256> table{};
    Unpremultiply() {
        for (unsigned a = 1; a < 256; ++a)
            for (unsigned c = 0; c < 256; ++c) {
                const unsigned v = (c * 255 + a / 2) / a;
                table[a][c] = static_cast<std::uint8_t>(v > 255 ? 255 : v);
            }
    }
};

}  // namespace

void unpremultiply(std::uint8_t* p, std::size_t count) {
    static const Unpremultiply u;
    for (std::size_t i = 0; i < count; ++i, p += 4) {
        const unsigned a = p[3];
        if (a == 255) continue;
        const auto& row = u.table[a];
        p[0] = row[p[0]], p[1] = row[p[1]], p[2] = row[p[2]];
    }
}

void composite_over(const std::uint8_t* src, int width, int height, std::uint8_t* dst,
                    int dst_stride, bool dst_transparent) {
    if (dst_transparent) {
        for (int y = 0; y < height; ++y) {
            const auto* s = src + static_cast<std::ptrdiff_t>(y) * width * 4;
            std::uint8_t* d = dst + static_cast<std::ptrdiff_t>(y) * dst_stride;
            for (int x = 0; x < width; ++x, s += 4, d += 4)
                if (s[3] != 0) std::memcpy(d, s, 4);
        }
        return;
    }
    for (int y = 0; y < height; ++y) {
        const std::uint8_t* s = src + static_cast<std::ptrdiff_t>(y) * width * 4;
        std::uint8_t* d = dst + static_cast<std::ptrdiff_t>(y) * dst_stride;
        int x = 0;
        // Two pixels per step while both are empty (most of a region's margins).
        for (; x < width; ++x, s += 4, d += 4) {
            if (x + 2 <= width) {
                std::uint64_t pair;
                std::memcpy(&pair, s, 8);
                if ((pair & 0xFF000000FF000000ull) == 0) {
                    ++x, s += 4, d += 4;
                    continue;
                }
            }
            const unsigned sa = s[3];
            if (sa == 0) continue;
            const unsigned da = d[3];
            if (sa == 255 || da == 0) {
                std::memcpy(d, s, 4);
                continue;
            }
            // out_a = sa + da (1 - sa); out_c = (sc sa + dc da (1 - sa)) / out_a, in 255ths.
            const unsigned k = da * (255 - sa);
            const unsigned a = sa * 255 + k;
            for (int c = 0; c < 3; ++c) {
                const unsigned v = (s[c] * sa * 255u + d[c] * k + a / 2) / a;
                d[c] = static_cast<std::uint8_t>(v > 255 ? 255 : v);
            }
            d[3] = static_cast<std::uint8_t>((a + 127) / 255);
        }
    }
}

}  // namespace endotower::gles
