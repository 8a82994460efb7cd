// MediaImage: one preoperative image decoded to straight-alpha RGBA 8-bit, ready for
// hal::OverlayRenderer::set_image.
//
// load_media_image(path): the format is told by the content, not the name: DICOM
// (the "DICM" mark at byte 128; DCMTK's DicomImage, first frame; monochrome with the
// file's first VOI window, else the min/max window, to grey; colour as RGB; JPEG/RLE
// transfer syntaxes included), PNG or JPEG (OpenCV; grey, RGB or RGBA, 8 or 16
// bits). Refused: a truncated PNG (no IEND) or JPEG (no end-of-image marker), a
// DICOM element longer than the file, images larger than kMaxSide on a side.
// Errors: false, and `error` is "PATH: what is wrong". Never throws.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "endotower/hal/overlay_renderer.hpp"

namespace endotower::media {

struct MediaImage {
    static constexpr int kMaxSide = 8192;
    std::string name;  // the file name, for the viewer's caption
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgba;  // rows packed, 4 * width bytes each

    hal::ImageView view() const { return {width, height, 4 * width, rgba.data()}; }
};

bool load_media_image(const std::string& path, MediaImage& out, std::string& error);

}  // namespace endotower::media
