#include "endotower/hal/control_input.hpp"
#include "endotower/hal/control_merge.hpp"
#include "endotower/hal/frame.hpp"

namespace endotower::hal {

namespace {
struct FormatName {
    PixelFormat format;
    std::string_view name;
};
constexpr FormatName kFormatNames[] = {
    {PixelFormat::kBgr24, "bgr24"}, {PixelFormat::kRgb24, "rgb24"},
    {PixelFormat::kBgra32, "bgra32"}, {PixelFormat::kGray8, "gray8"},
    {PixelFormat::kYuyv, "yuyv"},   {PixelFormat::kUyvy, "uyvy"},
    {PixelFormat::kNv12, "nv12"},
};
}  // namespace

std::string_view to_string(PixelFormat f) {
    for (const auto& n : kFormatNames)
        if (n.format == f) return n.name;
    return "unknown";
}

bool parse_pixel_format(std::string_view name, PixelFormat& out) {
    for (const auto& n : kFormatNames) {
        if (n.name == name) {
            out = n.format;
            return true;
        }
    }
    return false;
}

int bytes_per_pixel(PixelFormat f) {
    switch (f) {
        case PixelFormat::kBgr24:
        case PixelFormat::kRgb24: return 3;
        case PixelFormat::kBgra32: return 4;
        case PixelFormat::kYuyv:
        case PixelFormat::kUyvy: return 2;
        case PixelFormat::kGray8:
        case PixelFormat::kNv12: return 1;
    }
    return 0;
}

std::size_t FrameFormat::size_bytes() const {
    const auto rows = static_cast<std::size_t>(height);
    const auto luma = static_cast<std::size_t>(stride) * rows;
    // NV12's chroma plane: half the rows, same stride.
    return pixel_format == PixelFormat::kNv12 ? luma + luma / 2 : luma;
}

bool FrameFormat::valid() const {
    if (width <= 0 || height <= 0) return false;
    if (stride < width * bytes_per_pixel(pixel_format)) return false;
    if (pixel_format == PixelFormat::kNv12 && (width % 2 != 0 || height % 2 != 0)) return false;
    if ((pixel_format == PixelFormat::kYuyv || pixel_format == PixelFormat::kUyvy) && width % 2 != 0)
        return false;
    return true;
}

std::string_view to_string(ControlEvent::Kind k) {
    switch (k) {
        case ControlEvent::Kind::kButtonPress: return "press";
        case ControlEvent::Kind::kButtonRelease: return "release";
        case ControlEvent::Kind::kWheel: return "wheel";
        case ControlEvent::Kind::kLongPress: return "long_press";
    }
    return "unknown";
}

bool ControlMerge::attach(ControlInput* input) {
    if (count_ == kMaxInputs || input == nullptr) return false;
    slots_[count_++].input = input;
    return true;
}

bool ControlMerge::poll(ControlEvent& out) {
    Slot* oldest = nullptr;
    for (std::size_t i = 0; i < count_; ++i) {
        Slot& s = slots_[i];
        if (!s.has_pending) s.has_pending = s.input->poll(s.pending);
        if (s.has_pending && (oldest == nullptr || s.pending.time_ns < oldest->pending.time_ns))
            oldest = &s;
    }
    if (oldest == nullptr) return false;
    out = oldest->pending;
    oldest->has_pending = false;
    return true;
}

}  // namespace endotower::hal
