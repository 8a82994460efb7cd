// libFuzzer target: the calibration file (board `calibration:`, written by `endotower
// calibrate`). What parses must keep the parser's promises, survive a round trip through
// format_calibration(), and, for small images, build an undistortion map.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "endotower/calibration/calibration_file.hpp"
#include "endotower/calibration/undistorter.hpp"

using namespace endotower::calibration;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    Calibration c;
    std::string error;
    if (!parse_calibration(text, "fuzz.json", c, error)) {
        if (error.rfind("fuzz.json", 0) != 0) __builtin_trap();  // the file is named
        return 0;
    }
    if (c.width < 1 || c.height < 1 || c.width > 16384 || c.height > 16384) __builtin_trap();
    if (!(c.fx > 0) || !(c.fy > 0) || !(c.cx >= 0) || !(c.cx < c.width) || !(c.cy >= 0) ||
        !(c.cy < c.height))
        __builtin_trap();
    if (c.fov.valid() && !(c.fov.radius <= std::hypot(c.width, c.height))) __builtin_trap();
    Calibration back;
    if (!parse_calibration(format_calibration(c), "again.json", back, error)) __builtin_trap();
    if (back.width != c.width || back.distortion.size() != c.distortion.size()) __builtin_trap();
    if (c.width * c.height <= 128 * 128) {
        Undistorter u;
        if (u.init(c, error) && (u.width() != c.width || u.height() != c.height)) __builtin_trap();
    }
    return 0;
}
