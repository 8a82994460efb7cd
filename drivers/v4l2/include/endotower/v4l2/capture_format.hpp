// Capture format tables for V4L2: the board file's format names, their V4L2 fourcc
// codes, the hal pixel format the pipeline sees, and DV-timings names such as
// "1920x1080p60". Pure code (no device), unit tested on the host.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "endotower/hal/frame.hpp"

namespace endotower::v4l2 {

enum class CaptureFormat : std::uint8_t { kYuyv, kUyvy, kNv12, kMjpeg, kBgrx };

struct CaptureFormatInfo {
    CaptureFormat format;
    std::string_view name;   // board file name: "yuyv", "uyvy", "nv12", "mjpeg", "bgrx"
    std::uint32_t fourcc;    // V4L2_PIX_FMT_*
    hal::PixelFormat pixel;  // what the pipeline gets (MJPEG: decoded to BGR24)
    bool supported;          // false: refused at start() with `why`
    std::string_view why;
};

// The row for `f` (always found).
const CaptureFormatInfo& info(CaptureFormat f);
// Parses a board-file name. False if unknown.
bool parse_capture_format(std::string_view name, CaptureFormat& out);
// The row whose fourcc is `fourcc`, or nullptr.
const CaptureFormatInfo* find_fourcc(std::uint32_t fourcc);
// "YUYV" for V4L2_PIX_FMT_YUYV: the fourcc as four printable characters.
std::string fourcc_name(std::uint32_t fourcc);

// DV timings as the board file names them: WIDTHxHEIGHT{p|i}RATE, e.g. "1920x1080p60",
// "1280x720p59.94". Rate in Hz; tolerance when matching is 0.5 %.
struct DvTimingsName {
    int width = 0;
    int height = 0;
    bool interlaced = false;
    double hz = 0.0;
};
bool parse_dv_timings_name(std::string_view text, DvTimingsName& out);
// Refresh rate of BT.656/1120 timings: pixelclock / (total width * total height).
double dv_refresh_hz(std::uint64_t pixelclock, std::uint32_t total_width,
                     std::uint32_t total_height);
bool dv_matches(const DvTimingsName& want, int width, int height, bool interlaced, double hz);

}  // namespace endotower::v4l2
