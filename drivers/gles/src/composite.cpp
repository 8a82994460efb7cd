#include "composite.hpp"

#include <array>
#include <cstring>

namespace endotower::gles {

namespace {

// unpremultiply[a][c] = round(c * 255 / a), saturated: the common case of an overlay
// pixel over a transparent one needs no division.
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

const Unpremultiply& unpremultiply() {
    static const Unpremultiply u;
    return u;
}

}  // namespace

void composite_over(const std::uint8_t* src, int width, int height, std::uint8_t* dst,
                    int dst_stride) {
    const auto& unp = unpremultiply().table;
    for (int y = 0; y < height; ++y) {
        const std::uint8_t* s = src + static_cast<std::ptrdiff_t>(y) * width * 4;
        std::uint8_t* d = dst + static_cast<std::ptrdiff_t>(y) * dst_stride;
        int x = 0;
        while (x < width) {
            // Runs of empty overlay pixels (most of a region) are skipped 2 at a time.
            if (x + 2 <= width) {
                std::uint64_t pair;
                std::memcpy(&pair, s, 8);
                if (pair == 0) {
                    x += 2, s += 8, d += 8;
                    continue;
                }
            }
            const unsigned sa = s[3];
            const unsigned da = d[3];
            if (sa == 255) {
                std::memcpy(d, s, 4);
            } else if (sa == 0) {
            } else if (da == 0) {
                const auto& row = unp[sa];
                d[0] = row[s[0]], d[1] = row[s[1]], d[2] = row[s[2]];
                d[3] = static_cast<std::uint8_t>(sa);
            } else {
                // out_a = sa + da (1 - sa); out_c = (sc + dc da (1 - sa)) / out_a, in 255ths.
                const unsigned k = da * (255 - sa);
                const unsigned a = sa * 255 + k;
                for (int c = 0; c < 3; ++c) {
                    const unsigned v = (s[c] * 65025u + d[c] * k + a / 2) / a;
                    d[c] = static_cast<std::uint8_t>(v > 255 ? 255 : v);
                }
                d[3] = static_cast<std::uint8_t>((a + 127) / 255);
            }
            ++x, s += 4, d += 4;
        }
    }
}

}  // namespace endotower::gles
