// HighPassWindow: the image region propagation follows (docs/regions.md "Propagation"),
// written as an LkPyramid's base level: a window of a frame in grey (OpenCV's BGR->grey
// weights, 8-bit), reduced by area averaging when the frame is wider than the LK width
// (OpenCV's INTER_AREA rule: destination round(w * s) x round(h * s), each destination
// pixel the mean of its 1/s x 1/s source cell), then high-passed: minus its box mean
// (15x15 by default, reflected (101) borders). The endoscope carries its light, so
// shading moves with the camera; LK follows the texture instead.
// Hand-written because cv::resize(INTER_AREA) and cv::blur allocate on every call
// (1 to 5 and 8 heap allocations, OpenCV 4.6, measured with the allocation counter);
// this allocates only in reserve(). No exceptions.
#pragma once

#include <opencv2/core/types.hpp>
#include <vector>

#include "endotower/hal/frame.hpp"
#include "pyramid_lk.hpp"

namespace endotower::vision::detail {

class HighPassWindow {
public:
    explicit HighPassWindow(int box = 15) : radius_(box / 2) {}
    // Sizes the buffers for windows of frames up to width x height at scale s (0 < s <= 1;
    // allocates). The pyramid's reserve() must cover round(width * s) x round(height * s).
    void reserve(int width, int height, double s);
    // The window `roi` (inside the frame) of a Bgr24, Rgb24, Bgra32 or Gray8 frame into
    // pyr's base level, then pyr.build(). False (pyr untouched) for another format, an
    // empty or outside roi, or a frame larger than reserved.
    bool build(const hal::Frame& f, cv::Rect roi, LkPyramid& pyr);
    double scale() const { return s_; }
    // The window's size at the LK scale (what build() writes).
    cv::Size scaled(cv::Size roi) const;

private:
    struct Tap {
        int dst, src;
        float weight;
    };
    int area_table(int src_size, int dst_size, std::vector<Tap>& tab) const;
    void grey_row(const hal::Frame& f, int y, int x0, int width, float* out) const;
    void reduce_by(int k, const hal::Frame& f, cv::Rect roi, cv::Size d, float* area);
    int radius_;
    int factor_ = 0;  // 1/s when an integer (a block mean), else 0 (OpenCV's area table)
    double s_ = 1.0;
    int max_w_ = 0, max_h_ = 0;
    std::vector<Tap> xtab_, ytab_;
    std::vector<float> grey_, reduced_, area_, sums_;
    std::ptrdiff_t area_stride_ = 0;
};

}  // namespace endotower::vision::detail
