// libFuzzer target: the media folder's image loader (DICOM through DCMTK, PNG and
// JPEG through OpenCV), the parsers of files that come from outside. Input: the file,
// written to a per-process temporary file (DICOM is read from a file, see
// media_image.cpp). Either an image of a sane size comes back, or an error naming
// the file.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "endotower/media/media_image.hpp"
#include "fuzz_scratch_file.hpp"

using namespace endotower;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const fuzz::ScratchFile scratch("endotower_fuzz_media_");
    const std::string& path = scratch.path();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) __builtin_trap();
    if (size > 0 && std::fwrite(data, 1, size, f) != size) __builtin_trap();
    std::fclose(f);
    media::MediaImage img;
    std::string error;
    if (!media::load_media_image(path, img, error)) {
        if (error.rfind(path + ": ", 0) != 0 || !img.rgba.empty()) __builtin_trap();
        return 0;
    }
    if (img.width <= 0 || img.height <= 0 || img.width > media::MediaImage::kMaxSide ||
        img.height > media::MediaImage::kMaxSide ||
        img.rgba.size() != static_cast<std::size_t>(img.width) * img.height * 4)
        __builtin_trap();
    return 0;
}
