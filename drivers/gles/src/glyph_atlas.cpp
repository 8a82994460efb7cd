#include "glyph_atlas.hpp"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cstring>

namespace endotower::gles {

namespace {

constexpr int kAtlasWidth = 1024;
constexpr int kPad = 1;  // empty texels between glyphs: linear filtering never bleeds

struct Library {
    FT_Library lib = nullptr;
    FT_Face face = nullptr;
    ~Library() {
        if (face != nullptr) FT_Done_Face(face);
        if (lib != nullptr) FT_Done_FreeType(lib);
    }
};

std::string ft_error(const char* call, const std::string& path, FT_Error e) {
    const char* text = FT_Error_String(e);
    return std::string(call) + "(" + path + "): " + (text != nullptr ? text : "FreeType error") +
           " (" + std::to_string(e) + ")";
}

}  // namespace

std::uint32_t next_code_point(const char* s, std::size_t& i) {
    const auto b0 = static_cast<unsigned char>(s[i]);
    if (b0 < 0x80) {
        ++i;
        return b0;
    }
    int extra = 0;
    std::uint32_t cp = 0;
    if ((b0 & 0xE0) == 0xC0)
        extra = 1, cp = b0 & 0x1F;
    else if ((b0 & 0xF0) == 0xE0)
        extra = 2, cp = b0 & 0x0F;
    else if ((b0 & 0xF8) == 0xF0)
        extra = 3, cp = b0 & 0x07;
    else {
        ++i;
        return '?';
    }
    ++i;
    for (int k = 0; k < extra; ++k) {
        const auto b = static_cast<unsigned char>(s[i]);
        if ((b & 0xC0) != 0x80) return '?';  // a NUL or a new lead byte: not consumed
        cp = (cp << 6) | (b & 0x3F);
        ++i;
    }
    return cp;
}

bool GlyphAtlas::build(const std::string& font_path, std::string& error) {
    Library ft;
    FT_Error e = FT_Init_FreeType(&ft.lib);
    if (e != 0) {
        error = ft_error("FT_Init_FreeType", font_path, e);
        return false;
    }
    e = FT_New_Face(ft.lib, font_path.c_str(), 0, &ft.face);
    if (e != 0) {
        error = ft_error("FT_New_Face", font_path, e);
        return false;
    }
    // Two passes: measure the shelves, then copy the bitmaps.
    width_ = kAtlasWidth;
    for (int pass = 0; pass < 2; ++pass) {
        int x = kPad, y = kPad, shelf = 0;
        for (std::size_t f = 0; f < kPixelSizes.size(); ++f) {
            e = FT_Set_Pixel_Sizes(ft.face, 0, static_cast<FT_UInt>(kPixelSizes[f]));
            if (e != 0) {
                error = ft_error("FT_Set_Pixel_Sizes", font_path, e);
                return false;
            }
            GlyphFace& face = faces_[f];
            face.line_height = static_cast<int>((ft.face->size->metrics.height + 63) >> 6);
            face.ascender = static_cast<int>((ft.face->size->metrics.ascender + 63) >> 6);
            for (int c = 0; c < GlyphFace::kCount; ++c) {
                e = FT_Load_Char(
                    ft.face, static_cast<FT_ULong>(GlyphFace::kFirst) + static_cast<FT_ULong>(c),
                    FT_LOAD_RENDER);
                if (e != 0) {
                    error = ft_error("FT_Load_Char", font_path, e);
                    return false;
                }
                const FT_GlyphSlot g = ft.face->glyph;
                const int w = static_cast<int>(g->bitmap.width);
                const int h = static_cast<int>(g->bitmap.rows);
                if (x + w + kPad > width_) x = kPad, y += shelf + kPad, shelf = 0;
                Glyph& out = face.glyphs[static_cast<std::size_t>(c)];
                out.width = w;
                out.height = h;
                out.left = g->bitmap_left;
                out.top = g->bitmap_top;
                out.advance = static_cast<float>(g->advance.x) / 64.f;
                if (pass == 1) {
                    for (int r = 0; r < h; ++r)
                        std::memcpy(
                            &pixels_[static_cast<std::size_t>(y + r) * width_ + x],
                            g->bitmap.buffer + static_cast<std::ptrdiff_t>(r) * g->bitmap.pitch,
                            static_cast<std::size_t>(w));
                    out.u0 = static_cast<float>(x) / width_;
                    out.u1 = static_cast<float>(x + w) / width_;
                    out.v0 = static_cast<float>(y) / height_;
                    out.v1 = static_cast<float>(y + h) / height_;
                }
                x += w + kPad;
                shelf = std::max(shelf, h);
            }
        }
        if (pass == 0) {
            height_ = y + shelf + kPad;
            pixels_.assign(static_cast<std::size_t>(width_) * height_, 0);
        }
    }
    return true;
}

const GlyphFace& GlyphAtlas::pick(float line_height_px) const {
    for (const GlyphFace& f : faces_)
        if (static_cast<float>(f.line_height) >= line_height_px) return f;
    return faces_.back();
}

}  // namespace endotower::gles
