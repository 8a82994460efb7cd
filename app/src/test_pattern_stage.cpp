#include "endotower/app/test_pattern_stage.hpp"

#include <algorithm>
#include <cstring>
#include <opencv2/imgproc.hpp>

namespace endotower::app {

TestPatternStage::TestPatternStage(std::vector<std::string> prompts)
    : prompts_(std::move(prompts)) {}

hal::Rect TestPatternStage::bars_rect(int w, int h) {
    return {0, h - h / 12, w, h / 12};
}
hal::Rect TestPatternStage::banner_rect(int w, int h) {
    return {w / 8, h / 16, w - w / 4, h / 10};
}

void TestPatternStage::configure(const hal::FrameFormat& format) {
    width_ = format.width;
    height_ = format.height;
    const hal::Rect b = banner_rect(width_, height_);
    banners_.clear();
    const double scale = std::max(0.4, b.height / 110.0);
    const int thick = std::max(1, static_cast<int>(2 * scale));
    for (const std::string& p : prompts_) {
        // Dark translucent box, white text: readable over any video.
        cv::Mat rgba(b.height, b.width, CV_8UC4, cv::Scalar(0, 0, 0, 200));
        cv::putText(rgba, "ENDOTOWER SELFTEST", {b.height / 6, b.height * 2 / 5},
                    cv::FONT_HERSHEY_SIMPLEX, 0.8 * scale, cv::Scalar(255, 255, 0, 255), thick,
                    cv::LINE_AA);
        cv::putText(rgba, p, {b.height / 6, b.height * 5 / 6}, cv::FONT_HERSHEY_SIMPLEX, scale,
                    cv::Scalar(255, 255, 255, 255), thick, cv::LINE_AA);
        banners_.emplace_back(rgba.datastart, rgba.dataend);
    }
}

void TestPatternStage::process(AnalysisContext& ctx) {
    OverlayCanvas& c = ctx.overlay;
    const hal::Rect bars = bars_rect(c.width(), c.height());
    for (int i = 0; i < 8; ++i) {
        const int x0 = bars.width * i / 8, x1 = bars.width * (i + 1) / 8;
        c.fill({x0, bars.y, x1 - x0, bars.height}, kBars[i]);
    }
    const int p = prompt_.load(std::memory_order_relaxed);
    const hal::Rect b = banner_rect(c.width(), c.height());
    if (p >= 0 && p < static_cast<int>(banners_.size()) && c.width() == width_ &&
        c.height() == height_) {
        const std::vector<std::uint8_t>& src = banners_[static_cast<std::size_t>(p)];
        for (int y = 0; y < b.height; ++y)
            std::memcpy(c.row(b.y + y) + 4 * b.x,
                        src.data() + static_cast<std::size_t>(y) * b.width * 4,
                        static_cast<std::size_t>(b.width) * 4);
        c.mark(b);
    }
    ctx.trace.field("selftest_prompt", p);
}

}  // namespace endotower::app
