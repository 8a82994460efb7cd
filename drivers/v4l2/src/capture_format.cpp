#include "endotower/v4l2/capture_format.hpp"

#include <linux/videodev2.h>

#include <charconv>
#include <cmath>

namespace endotower::v4l2 {

namespace {
constexpr CaptureFormatInfo kFormats[] = {
    {CaptureFormat::kYuyv, "yuyv", V4L2_PIX_FMT_YUYV, hal::PixelFormat::kYuyv, true, ""},
    {CaptureFormat::kUyvy, "uyvy", V4L2_PIX_FMT_UYVY, hal::PixelFormat::kUyvy, true, ""},
    {CaptureFormat::kNv12, "nv12", V4L2_PIX_FMT_NV12, hal::PixelFormat::kNv12, true, ""},
    // B G R X bytes (V4L2 XBGR32 = DRM XRGB8888): what a display plane without YUV
    // takes directly, so the DMABUF is scanned out without a copy (vivid -> vkms).
    {CaptureFormat::kBgrx, "bgrx", V4L2_PIX_FMT_XBGR32, hal::PixelFormat::kBgra32, true, ""},
    // Decoded to BGR24 by MjpegDecoder into a frame of the driver's (no DMABUF).
    {CaptureFormat::kMjpeg, "mjpeg", V4L2_PIX_FMT_MJPEG, hal::PixelFormat::kBgr24, true, ""},
};
}  // namespace

const CaptureFormatInfo& info(CaptureFormat f) {
    for (const auto& row : kFormats)
        if (row.format == f) return row;
    return kFormats[0];
}

bool parse_capture_format(std::string_view name, CaptureFormat& out) {
    for (const auto& row : kFormats) {
        if (row.name == name) {
            out = row.format;
            return true;
        }
    }
    return false;
}

const CaptureFormatInfo* find_fourcc(std::uint32_t fourcc) {
    for (const auto& row : kFormats)
        if (row.fourcc == fourcc) return &row;
    return nullptr;
}

std::string fourcc_name(std::uint32_t fourcc) {
    std::string s(4, ' ');
    for (int i = 0; i < 4; ++i) {
        const char c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
        s[i] = c >= 32 && c < 127 ? c : '?';
    }
    return s;
}

bool parse_dv_timings_name(std::string_view t, DvTimingsName& out) {
    DvTimingsName d;
    const char* p = t.data();
    const char* end = t.data() + t.size();
    auto r = std::from_chars(p, end, d.width);
    if (r.ec != std::errc() || r.ptr == end || *r.ptr != 'x') return false;
    r = std::from_chars(r.ptr + 1, end, d.height);
    if (r.ec != std::errc() || r.ptr == end || (*r.ptr != 'p' && *r.ptr != 'i')) return false;
    d.interlaced = *r.ptr == 'i';
    r = std::from_chars(r.ptr + 1, end, d.hz);
    if (r.ec != std::errc() || r.ptr != end) return false;
    if (d.width <= 0 || d.height <= 0 || d.width > 16384 || d.height > 16384 || !(d.hz > 0) ||
        d.hz > 1000)
        return false;
    out = d;
    return true;
}

double dv_refresh_hz(std::uint64_t pixelclock, std::uint32_t total_width,
                     std::uint32_t total_height) {
    if (total_width == 0 || total_height == 0) return 0.0;
    return static_cast<double>(pixelclock) / (static_cast<double>(total_width) * total_height);
}

bool dv_matches(const DvTimingsName& want, int width, int height, bool interlaced, double hz) {
    return want.width == width && want.height == height && want.interlaced == interlaced &&
           std::fabs(hz - want.hz) <= 0.005 * want.hz;
}

}  // namespace endotower::v4l2
