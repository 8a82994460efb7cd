// MaskOps: the binary-image operations of the gesture segmenter, allocation-free and
// single-threaded, each giving exactly the bytes (or values) of the OpenCV call it
// replaces (tested against it):
//   lit_field   cv::blur 9x9 (reflect-101 borders) then cv::threshold BINARY, with the
//               result's pixel count and coordinate sums (cv::moments(binary) m00/m10/m01);
//   morph       cv::erode / cv::dilate with a structuring element given per row as a
//               centred half-width (-1: empty row, at most 7; e.g. MORPH_ELLIPSE 7x7 is
//               0,2,3,3,3,2,0: ellipse_rows), the border ignored (the default border
//               value), in != out;
//   open3       cv::morphologyEx MORPH_OPEN with a 3x3 square;
//   smooth_at_least  cv::GaussianBlur 5x5, sigma 1.2 (8-bit: OpenCV's bit-exact fixed
//               point, taps 22 62 88 62 22 / 256 each way, reflect-101, rounded), then
//               >= threshold and nonzero in `and_mask` gives 255, else 0 (and, when
//               `smoothed` is given, the blurred bytes themselves);
//   label       cv::connectedComponentsWithStats, 8-connected: labels 1..n-1 in the order
//               of each component's first pixel in raster order (0 = background), its
//               area and bounding box; returns n;
//   chamfer     cv::distanceTransform DIST_L2 with the 3x3 mask (weights 0.955 / 1.3693
//               in 16.16 fixed point, the values it returns times 65536) inside a
//               rectangle only: exact for every pixel whose 8-connected component, one
//               pixel around, lies in the rectangle or beyond the image's edge.
// configure() sizes the scratch buffers for images up to width x height (the only
// allocation); the operations take borrowed planes of at most that size. No exceptions.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace endotower::vision {

struct BytePlane {  // borrowed 8-bit image
    std::uint8_t* data = nullptr;
    int width = 0, height = 0;
    std::size_t stride = 0;
    std::uint8_t* row(int y) const { return data + static_cast<std::size_t>(y) * stride; }
};

struct LitMoments {
    double m00 = 0, m10 = 0, m01 = 0;
};

struct Component {
    int left = 0, top = 0, right = 0, bottom = 0;  // inclusive
    int area = 0;
};

class MaskOps {
public:
    void configure(int width, int height);
    LitMoments lit_field(BytePlane gray, int threshold, BytePlane lit);
    void morph(BytePlane in, BytePlane out, std::span<const int> half_widths, bool erode);
    // The rows of cv::getStructuringElement(MORPH_ELLIPSE, 2 r + 1) as morph() takes them,
    // r in 0..7 (clamped); returns their number, 2 r + 1.
    static int ellipse_rows(int r, std::array<int, 15>& rows);
    void open3(BytePlane in, BytePlane out);  // in and out may be the same plane
    void smooth_at_least(BytePlane in, int threshold, BytePlane and_mask, BytePlane out,
                         BytePlane smoothed = {});
    int label(BytePlane mask, std::int32_t* labels);  // labels: width x height, packed
    // The same for a part of a larger image: `labels` rows `stride` apart, and the
    // components' boxes offset by (x0, y0), the part's place in that image.
    int label(BytePlane mask, std::int32_t* labels, std::size_t stride, int x0, int y0);
    const std::vector<Component>& components() const { return components_; }  // per label
    void chamfer(BytePlane mask, int x0, int y0, int x1, int y1, std::uint32_t* out);
    // Sizes chamfer()'s buffer alone, for images up to width x height: a MaskOps that
    // only measures distances (one per thread measuring regions).
    void configure_chamfer(int width, int height);

private:
    int width_ = 0, height_ = 0;
    std::vector<std::uint32_t> columns_, padded_sums_, box_;
    std::vector<std::uint16_t> rows_;  // smooth_at_least's horizontal pass
    std::vector<std::uint8_t> padded_, spans_, tmp_;
    struct Run {
        int y = 0, start = 0, end = 0;  // [start, end) of row y
    };
    std::vector<Run> runs_;
    std::vector<std::int32_t> parent_;
    std::vector<Component> components_;
    std::vector<std::uint32_t> chamfer_;
};

}  // namespace endotower::vision
