// GrayImage: an owned 8-bit single-channel image, the input of every calibration
// step (calibration is offline: images come from files or copied live frames).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "endotower/hal/frame.hpp"

namespace endotower::calibration {

struct Point2 {
    double x = 0, y = 0;
};

struct GrayImage {
    int width = 0, height = 0;
    std::vector<std::uint8_t> pixels;  // row-major, width bytes per row
    std::string name;                  // where it came from (file name), for messages

    bool empty() const { return width <= 0 || height <= 0; }
    std::uint8_t at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x]; }
};

// Reads an image file (any format OpenCV reads) as grayscale. False with `error`
// naming the file when it cannot be read.
bool load_gray_image(const std::string& path, GrayImage& out, std::string& error);

// Copies a frame (bgr24, rgb24, bgra32, gray8, yuyv, uyvy, nv12) to grayscale (luma).
// False when the format is not valid.
bool gray_from_frame(const hal::Frame& frame, GrayImage& out);

// The image files of a folder (png, jpg, jpeg, bmp, tif, tiff; any case), sorted by
// name. False with `error` when the folder cannot be read or holds none.
bool list_images(const std::string& dir, std::vector<std::string>& paths, std::string& error);

}  // namespace endotower::calibration
