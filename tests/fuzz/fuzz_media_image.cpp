// libFuzzer target: the media folder's image decoders (DICOM through DCMTK, PNG and
// JPEG through OpenCV), the parsers of files that come from outside. Input: the file.
// Either an image of a sane size comes back, or an error naming the file.
#include <cstddef>
#include <cstdint>
#include <string>

#include "endotower/media/media_image.hpp"

using namespace endotower;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    media::MediaImage img;
    std::string error;
    if (!media::decode_media_image(data, size, "fuzz.img", img, error)) {
        if (error.rfind("fuzz.img: ", 0) != 0 || !img.rgba.empty()) __builtin_trap();
        return 0;
    }
    if (img.width <= 0 || img.height <= 0 || img.width > media::MediaImage::kMaxSide ||
        img.height > media::MediaImage::kMaxSide ||
        img.rgba.size() != static_cast<std::size_t>(img.width) * img.height * 4)
        __builtin_trap();
    return 0;
}
