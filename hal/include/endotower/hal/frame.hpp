// Frame value types: pixel formats, frame geometry and a borrowed view of one
// captured buffer. No pixels are owned here; the FrameSource owns the buffers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "endotower/hal/time.hpp"

namespace endotower::hal {

enum class PixelFormat : std::uint8_t {
    kBgr24,   // 3 bytes/pixel, B G R (OpenCV's native order)
    kRgb24,   // 3 bytes/pixel, R G B
    kBgra32,  // 4 bytes/pixel, B G R A (DRM XRGB8888/ARGB8888 little-endian)
    kGray8,   // 1 byte/pixel
    kYuyv,    // packed 4:2:2, Y0 U Y1 V
    kUyvy,    // packed 4:2:2, U Y0 V Y1
    kNv12,    // planar Y, then interleaved UV at half resolution
};

std::string_view to_string(PixelFormat f);
// Parses the names printed by to_string ("bgr24", "yuyv", ...). False if unknown.
bool parse_pixel_format(std::string_view name, PixelFormat& out);
// Bytes per pixel of the first plane (2 for the packed 4:2:2 formats, 1 for NV12's Y).
int bytes_per_pixel(PixelFormat f);

struct FrameFormat {
    int width = 0;
    int height = 0;
    int stride = 0;  // bytes per row of the first plane, >= width * bytes_per_pixel
    PixelFormat pixel_format = PixelFormat::kBgr24;

    // Total bytes of all planes.
    std::size_t size_bytes() const;
    bool valid() const;
    friend bool operator==(const FrameFormat&, const FrameFormat&) = default;
};

// A borrowed view of one buffer of a FrameSource. Valid from FrameSource::next()
// until it is given back with FrameSource::release(); never copied by the pipeline.
struct Frame {
    FrameFormat format;
    std::uint8_t* data = nullptr;  // first plane; planes are contiguous
    Nanos capture_ns = 0;          // capture timestamp, monotonic clock
    std::uint64_t sequence = 0;    // source sequence number; gaps mean dropped frames
    int buffer_index = -1;         // which buffer of the source's pool this is
    int dmabuf_fd = -1;            // the buffer exported as DMABUF (owned by the source), or -1
};

}  // namespace endotower::hal
