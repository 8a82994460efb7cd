// AreaMean: the reduction cv::resize makes with INTER_AREA, for any factor of at least 1
// in each direction, with its bytes and without its allocation: cv::resize builds its
// weight tables and row buffers on every call, AreaMean once in configure().
//
// An integer factor k (1..15, the same in both directions) goes through BlockMean
// (OpenCV's block path). Any other factor follows OpenCV's general area path: each
// output pixel is the float sum of the input pixels it covers, each weighted by the
// fraction of it that is covered (over the cell's area), a pixel cut by the cell's
// border counting in part, then rounded half to even. Tested against cv::resize for
// the sizes the analysis stages meet (384x288, 720x576, 1000x700 to 320 wide).
//
// configure() returns false where OpenCV would not take one of these paths (a factor
// below 1, unequal integer factors, an integer factor over 15); run() then does
// nothing. Callers check fits() with each frame's size: a frame of another size than
// configured must not reach run(). run() reads `src` (rows of `src_stride` bytes) and writes `dst`
// (rows of `dst_stride` bytes); no exceptions, no allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "endotower/vision/block_mean.hpp"

namespace endotower::vision {

class AreaMean {
public:
    bool configure(int src_width, int src_height, int dst_width, int dst_height, int channels);
    bool ready() const { return block_.ready() || !row_start_.empty(); }
    // Ready, and configured for a source of this size (run() reads that many pixels).
    bool fits(int src_width, int src_height) const {
        return ready() && src_width == src_width_ && src_height == src_height_;
    }
    void run(const std::uint8_t* src, std::size_t src_stride, std::uint8_t* dst,
             std::size_t dst_stride);

    struct Weight {
        int dst = 0;  // output index (x: element, y: row)
        int src = 0;  // input index (x: element, y: row)
        float alpha = 0;
    };

private:
    void column_sums(const std::uint8_t* row, float* line) const;

    BlockMean block_;
    std::vector<Weight> columns_, rows_;
    std::vector<int> row_start_;  // rows_ of output row y: [row_start_[y], row_start_[y + 1])
    std::vector<float> line_, sum_;
    int channels_ = 0, src_width_ = 0, src_height_ = 0;
};

}  // namespace endotower::vision
