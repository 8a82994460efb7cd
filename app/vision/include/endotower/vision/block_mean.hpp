// BlockMean: reduces an 8-bit image of `channels` interleaved channels by an integer
// factor k (1..15) in both directions, each output pixel the mean of its k x k input
// block rounded to the nearest integer as cv::resize's INTER_AREA integer-factor path
// rounds it: ties up for k = 2, to even for even k >= 4 (sum x float(1 / k^2)), none
// for odd k. So these are its bytes (tested for k = 1..8), in one pass over the input
// with one row of column sums, no threads and no allocation (cv::resize allocates its
// tables per call).
//
// configure() sizes the buffers (the only allocation) and returns false when the
// sizes are not an integer factor apart (k = 1, a copy, included); run() then does
// nothing. run() reads `src` (rows of `src_stride` bytes) and writes `dst` (rows of
// `dst_stride` bytes); no exceptions, no allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace endotower::vision {

class BlockMean {
public:
    bool configure(int src_width, int src_height, int dst_width, int dst_height, int channels);
    bool ready() const { return factor_ > 0; }
    int factor() const { return factor_; }
    void run(const std::uint8_t* src, std::size_t src_stride, std::uint8_t* dst,
             std::size_t dst_stride);

private:
    int factor_ = 0, channels_ = 0, dst_width_ = 0, dst_height_ = 0;
    std::vector<std::uint16_t> columns_;  // one output row's k-row column sums
    std::vector<std::uint16_t> sums_;     // k = 2, 4, 6 (3 channels): k-pixel sums
    std::vector<std::uint8_t> means_;     // k = 3 (3 channels): every position's mean
    std::vector<std::uint8_t> mean_;      // block sum -> rounded mean
};

}  // namespace endotower::vision
