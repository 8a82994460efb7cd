#include "endotower/app/status_badge.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace endotower::app {

namespace {
constexpr char kFirstGlyph = ' ';
constexpr char kLastGlyph = '~';
constexpr int kGlyphCount = kLastGlyph - kFirstGlyph + 1;

// Luma of one pixel, BT.601 weights in 8-bit fixed point.
inline int luma_bgr(const std::uint8_t* p) { return (29 * p[0] + 150 * p[1] + 77 * p[2]) >> 8; }
inline int luma_rgb(const std::uint8_t* p) { return (77 * p[0] + 150 * p[1] + 29 * p[2]) >> 8; }
}  // namespace

void StatusBadge::measure(const hal::Frame& frame, int step, double& light, double& clipped) {
    const hal::FrameFormat& f = frame.format;
    std::int64_t sum = 0, n = 0, hot = 0;
    for (int y = 0; y < f.height; y += step) {
        const std::uint8_t* row = frame.data + static_cast<std::ptrdiff_t>(y) * f.stride;
        for (int x = 0; x < f.width; x += step) {
            int l = 0;
            switch (f.pixel_format) {
                case hal::PixelFormat::kBgr24: l = luma_bgr(row + 3 * x); break;
                case hal::PixelFormat::kRgb24: l = luma_rgb(row + 3 * x); break;
                case hal::PixelFormat::kBgra32: l = luma_bgr(row + 4 * x); break;
                case hal::PixelFormat::kGray8:
                case hal::PixelFormat::kNv12: l = row[x]; break;
                case hal::PixelFormat::kYuyv: l = row[2 * x]; break;
                case hal::PixelFormat::kUyvy: l = row[2 * x + 1]; break;
            }
            if (l <= kSurround) continue;
            sum += l;
            hot += l >= 250;
            ++n;
        }
    }
    light = n > 0 ? static_cast<double>(sum) / (255.0 * static_cast<double>(n)) : 0.0;
    clipped = n > 0 ? static_cast<double>(hot) / static_cast<double>(n) : 0.0;
}

void StatusBadge::configure(const hal::FrameFormat& format) {
    // Hershey simplex at a size readable on a 24" monitor: ~1.6 % of the height.
    scale_ = std::max(1, format.height / 540);
    const double font_scale = 0.45 * scale_;
    const int thickness = scale_;
    int baseline = 0;
    const cv::Size box = cv::getTextSize("W", cv::FONT_HERSHEY_SIMPLEX, font_scale, thickness, &baseline);
    cell_w_ = box.width + scale_;
    cell_h_ = box.height + baseline + 2 * scale_;
    glyphs_.assign(static_cast<std::size_t>(kGlyphCount) * cell_w_ * cell_h_, 0);
    for (int g = 0; g < kGlyphCount; ++g) {
        cv::Mat cell(cell_h_, cell_w_, CV_8UC1, glyphs_.data() + static_cast<std::size_t>(g) * cell_w_ * cell_h_);
        const char text[2] = {static_cast<char>(kFirstGlyph + g), 0};
        cv::putText(cell, text, cv::Point(0, cell_h_ - baseline - scale_), cv::FONT_HERSHEY_SIMPLEX,
                    font_scale, cv::Scalar(255), thickness, cv::LINE_AA);
        int b = 0;
        advance_[static_cast<std::size_t>(g)] =
            cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, font_scale, thickness, &b).width + scale_;
    }
    button_down_ = false;
    wheel_total_ = 0;
}

int StatusBadge::text_width(const char* text) const {
    int w = 0;
    for (int i = 0; text[i] != 0; ++i)
        if (text[i] >= kFirstGlyph && text[i] <= kLastGlyph) w += advance_[static_cast<std::size_t>(text[i] - kFirstGlyph)];
    return w;
}

void StatusBadge::draw_text(OverlayCanvas& canvas, int x0, int y0, const char* text) const {
    int gx = x0;
    for (int i = 0; text[i] != 0; ++i) {
        const char c = text[i];
        if (c < kFirstGlyph || c > kLastGlyph) continue;
        const std::uint8_t* glyph =
            glyphs_.data() + static_cast<std::size_t>(c - kFirstGlyph) * cell_w_ * cell_h_;
        const int advance = advance_[static_cast<std::size_t>(c - kFirstGlyph)];
        for (int y = 0; y < cell_h_; ++y) {
            const int py = y0 + y;
            if (py < 0 || py >= canvas.height()) continue;
            std::uint8_t* row = canvas.row(py);
            for (int x = 0; x < cell_w_; ++x) {
                const int px = gx + x;
                const std::uint8_t a = glyph[y * cell_w_ + x];
                if (a == 0 || px < 0 || px >= canvas.width()) continue;
                // White text over the badge background: blend towards white by coverage.
                std::uint8_t* p = row + 4 * px;
                for (int ch = 0; ch < 3; ++ch) p[ch] = static_cast<std::uint8_t>(p[ch] + ((255 - p[ch]) * a + 127) / 255);
                p[3] = static_cast<std::uint8_t>(p[3] + ((255 - p[3]) * a + 127) / 255);
            }
        }
        gx += advance;
    }
}

void StatusBadge::process(AnalysisContext& ctx) {
    for (const hal::ControlEvent& e : ctx.events) {
        if (e.kind == hal::ControlEvent::Kind::kButtonPress && e.button == 0) button_down_ = true;
        if (e.kind == hal::ControlEvent::Kind::kButtonRelease && e.button == 0) button_down_ = false;
        if (e.kind == hal::ControlEvent::Kind::kWheel) wheel_total_ += e.delta;
    }
    double light = 0, clipped = 0;
    measure(ctx.frame, step_, light, clipped);
    const int percent = static_cast<int>(std::lround(light * 100.0));
    const char* band = percent < 30 ? "0-30" : percent <= 45 ? "30-45" : "46-100";

    char text[48];
    std::snprintf(text, sizeof text, "LIGHT %d%%%s", percent, button_down_ ? "  BTN" : "");
    const int pad = 4 * scale_;
    const hal::Rect box{8 * scale_, 8 * scale_, text_width(text) + 2 * pad + 3 * cell_h_ / 2, cell_h_ + 2 * pad};
    ctx.overlay.fill(box, Rgba{20, 20, 20, 170});
    // The light band as a coloured square at the badge's left.
    const Rgba band_colour = percent < 30 ? Rgba{230, 40, 40, 255}
                             : percent <= 45 ? Rgba{240, 170, 20, 255}
                                             : Rgba{40, 200, 80, 255};
    const int sq = cell_h_ - 2 * scale_;
    ctx.overlay.fill({box.x + pad, box.y + pad + scale_, sq, sq}, band_colour);
    draw_text(ctx.overlay, box.x + pad + sq + cell_h_ / 2, box.y + pad, text);

    ctx.trace.begin_object("status")
        .field("light", light)
        .field("clipped", clipped)
        .field("band", band)
        .field("button_down", button_down_)
        .field("wheel", wheel_total_)
        .end_object();
}

}  // namespace endotower::app
