// GlyphAtlas: the font's glyphs U+0020..U+00FF (Basic Latin and Latin-1, enough for
// names and notes in western languages; other code points draw as '?') rasterised by
// FreeType at a few pixel sizes into one 8-bit coverage image, shelf-packed.
// Built once (configure); then read-only, no allocation.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace endotower::gles {

struct Glyph {
    float u0 = 0, v0 = 0, u1 = 0, v1 = 0;  // in the atlas, 0..1
    int width = 0, height = 0;               // bitmap pixels
    int left = 0, top = 0;                   // bearing from the pen on the baseline (top up)
    float advance = 0;                       // pixels
};

struct GlyphFace {
    static constexpr int kFirst = 0x20, kCount = 0xE0;
    int line_height = 0, ascender = 0;  // pixels
    std::array<Glyph, kCount> glyphs{};
    const Glyph& at(std::uint32_t code_point) const {
        if (code_point < kFirst || code_point >= kFirst + kCount) code_point = '?';
        return glyphs[code_point - kFirst];
    }
};

class GlyphAtlas {
public:
    static constexpr std::array<int, 8> kPixelSizes = {10, 14, 18, 24, 32, 40, 52, 64};

    // Loads `font_path`; false with `error` naming the file and FreeType's code.
    bool build(const std::string& font_path, std::string& error);

    // The smallest face whose line height is at least `line_height_px` (else the largest).
    const GlyphFace& pick(float line_height_px) const;

    int width() const { return width_; }
    int height() const { return height_; }
    const std::vector<std::uint8_t>& coverage() const { return pixels_; }

private:
    std::array<GlyphFace, kPixelSizes.size()> faces_{};
    int width_ = 0, height_ = 0;
    std::vector<std::uint8_t> pixels_;
};

// Decodes one UTF-8 code point at s[i], advancing i; malformed bytes give '?'.
std::uint32_t next_code_point(const char* s, std::size_t& i);

}  // namespace endotower::gles
