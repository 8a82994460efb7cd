#include "endotower/app/no_signal_source.hpp"

#include <algorithm>
#include <cstring>
#include <opencv2/imgproc.hpp>

namespace endotower::app {

NoSignalSource::NoSignalSource(hal::FrameSource& inner, hal::Clock& clock, Log& log,
                               hal::Nanos after_ns)
    : inner_(inner),
      clock_(clock),
      log_(log),
      after_ns_(after_ns > 0 ? after_ns : 250 * hal::kMillisecond) {}

bool NoSignalSource::start() {
    if (!inner_.start()) return false;
    render(inner_.format());
    last_frame_ns_ = clock_.now();
    return true;
}

void NoSignalSource::render(const hal::FrameFormat& f) {
    card_format_ = f;
    card_.assign(f.size_bytes(), 0);
    // The words as luma, then written in the frame's own pixel layout.
    cv::Mat luma(f.height, f.width, CV_8UC1, cv::Scalar(0));
    const double scale = std::max(1.0, f.height / 270.0);
    const int thick = std::max(2, static_cast<int>(scale * 2));
    auto centred = [&](const char* text, double s, int y) {
        int base = 0;
        const cv::Size sz = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, s, thick, &base);
        cv::putText(luma, text, {(f.width - sz.width) / 2, y}, cv::FONT_HERSHEY_SIMPLEX, s,
                    cv::Scalar(255), thick, cv::LINE_AA);
    };
    centred("NO SIGNAL", scale * 1.2, f.height / 2);
    centred("check the camera and its cable", scale * 0.45,
            f.height / 2 + static_cast<int>(40 * scale));

    const int w = f.width, h = f.height;
    for (int y = 0; y < h; ++y) {
        const std::uint8_t* l = luma.ptr<std::uint8_t>(y);
        std::uint8_t* row = card_.data() + static_cast<std::size_t>(y) * f.stride;
        switch (f.pixel_format) {
            case hal::PixelFormat::kYuyv:
            case hal::PixelFormat::kUyvy: {
                const int yoff = f.pixel_format == hal::PixelFormat::kYuyv ? 0 : 1;
                for (int x = 0; x < w; ++x) {
                    row[2 * x + yoff] =
                        static_cast<std::uint8_t>(16 + l[x] * 219 / 255);  // limited range
                    row[2 * x + 1 - yoff] = 128;
                }
                break;
            }
            case hal::PixelFormat::kNv12:
            case hal::PixelFormat::kGray8:
                for (int x = 0; x < w; ++x)
                    row[x] = f.pixel_format == hal::PixelFormat::kNv12
                                 ? static_cast<std::uint8_t>(16 + l[x] * 219 / 255)
                                 : l[x];
                break;
            case hal::PixelFormat::kBgr24:
            case hal::PixelFormat::kRgb24:
                for (int x = 0; x < w; ++x) row[3 * x] = row[3 * x + 1] = row[3 * x + 2] = l[x];
                break;
            case hal::PixelFormat::kBgra32:
                for (int x = 0; x < w; ++x)
                    row[4 * x] = row[4 * x + 1] = row[4 * x + 2] = l[x], row[4 * x + 3] = 255;
                break;
        }
    }
    if (f.pixel_format == hal::PixelFormat::kNv12)  // neutral chroma
        std::memset(card_.data() + static_cast<std::size_t>(f.stride) * h, 128,
                    card_.size() - static_cast<std::size_t>(f.stride) * h);
}

hal::SourceStatus NoSignalSource::next(hal::Frame& out, hal::Nanos timeout_ns) {
    const hal::SourceStatus st = inner_.next(out, timeout_ns);
    const hal::Nanos now = clock_.now();
    if (st == hal::SourceStatus::kFrame) {
        if (showing_) log_.write(LogLevel::kInfo, "capture signal is back");
        showing_ = false;
        last_frame_ns_ = now;
        last_sequence_ = out.sequence;
        return st;
    }
    if (st == hal::SourceStatus::kFormatChange) {
        render(inner_.format());  // the pipeline has given back every frame by now
        return st;
    }
    if (st != hal::SourceStatus::kTimeout || now - last_frame_ns_ < after_ns_) return st;
    if (!showing_)
        log_.write(LogLevel::kWarning,
                   "no signal from the capture input; showing the no-signal screen");
    showing_ = true;
    if (!(card_format_ == inner_.format())) return st;  // a format change is on its way
    out = hal::Frame{};
    out.format = card_format_;
    out.data = card_.data();
    out.capture_ns = now;
    out.sequence = last_sequence_;
    out.buffer_index = kCardIndex;
    return hal::SourceStatus::kFrame;
}

void NoSignalSource::release(const hal::Frame& frame) {
    if (frame.buffer_index != kCardIndex) inner_.release(frame);
}

}  // namespace endotower::app
