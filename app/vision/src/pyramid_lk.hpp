// Pyramidal Lucas-Kanade over preallocated float pyramids, for the region's per-frame
// propagation (docs/regions.md "Propagation"). Hand-written because OpenCV's
// buildOpticalFlowPyramid + calcOpticalFlowPyrLK allocate on every call (4 + 7 heap
// allocations per frame single-threaded, about 500 with its thread pool, OpenCV 4.6,
// measured with the allocation counter); this allocates only in reserve().
//
// LkPyramid: one image's levels, each padded by kBorder reflected (101) pixels so LK's
//   window may overlap the edge. reserve() sizes them for base images up to a size;
//   write the base level through base(), then build(): the border, then each level the
//   5x5 Gaussian pyrDown of the one below ((w + 1) / 2 x (h + 1) / 2), as OpenCV's, up
//   to max_level while a level stays larger than the window.
// PyramidLk::track(): OpenCV's algorithm (Bouguet), in float: per point, from the top
//   level down, the window's gradients (Scharr, at the previous point's sub-pixel
//   position) give G; Newton steps on the mismatch move the point until the step is
//   below epsilon, max_iterations, or it oscillates (the half step back). A point fails
//   (status 0) when its window leaves the padded base level or G's smaller eigenvalue per
//   window pixel is below min_eigen (OpenCV's units, 1e-4 as its default).
// No allocation and no exceptions in build() and track().
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core/types.hpp>
#include <span>
#include <vector>

namespace endotower::vision::detail {

struct LkParams {
    int window = 15;  // odd, 3..15
    int max_level = 3;
    int max_iterations = 20;
    double epsilon = 0.03;  // px at the level
    double min_eigen = 1e-4;
};

class LkPyramid {
public:
    static constexpr int kBorder = 18;  // a window row of 16 and a pixel each side
    struct Level {
        const float* data = nullptr;  // pixel (0, 0); the border lies before and after
        std::ptrdiff_t stride = 0;    // floats per row
        int width = 0, height = 0;
        float at(int x, int y) const { return data[y * stride + x]; }
    };
    // Allocates the levels for base images up to max_width x max_height.
    void reserve(int max_width, int max_height, const LkParams& p);
    // The base level, width x height: row y starts at base(...) + y * level(0).stride;
    // nullptr when larger than reserved. Then build().
    float* base(int width, int height);
    void build();
    int levels() const { return levels_; }
    Level level(int l) const;
    int border() const { return border_; }

private:
    struct Plane {
        std::vector<float> buf;
        int cap_w = 0, cap_h = 0, width = 0, height = 0;
        std::ptrdiff_t stride = 0;
    };
    float* origin(Plane& p) const;
    void pad(Plane& p) const;
    std::vector<Plane> planes_;
    std::vector<float> row_;
    int border_ = 0, levels_ = 0, max_level_ = 0, window_ = 15;
};

class PyramidLk {
public:
    explicit PyramidLk(LkParams p = {});
    const LkParams& params() const { return p_; }
    // next_pts[i]: prev_pts[i] (prev's base pixels) found in next; status[i] 1 when found.
    // The spans are of one size; the pyramids must come from the same reserve() sizes.
    void track(const LkPyramid& prev, const LkPyramid& next, std::span<const cv::Point2f> prev_pts,
               std::span<cv::Point2f> next_pts, std::span<std::uint8_t> status) const;

private:
    LkParams p_;
};

}  // namespace endotower::vision::detail
