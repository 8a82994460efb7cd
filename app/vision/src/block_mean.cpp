// BlockMean: an integer-factor box reduction (block_mean.hpp).
#include "endotower/vision/block_mean.hpp"

#include <cmath>
#include <cstring>

#include "wide_vectors.hpp"

namespace endotower::vision {

bool BlockMean::configure(int src_width, int src_height, int dst_width, int dst_height,
                          int channels) {
    factor_ = 0;
    if (dst_width <= 0 || dst_height <= 0 || channels <= 0 || src_width % dst_width != 0)
        return false;
    const int k = src_width / dst_width;
    // Column sums of k rows (255 k) stay in 16 bits; k <= 15 keeps the mean table small.
    if (k < 1 || k > 15 || src_height != k * dst_height) return false;
    factor_ = k;
    channels_ = channels;
    dst_width_ = dst_width;
    dst_height_ = dst_height;
    columns_.assign(static_cast<std::size_t>(src_width) * channels, 0);
    // Each 3-channel row path's scratch row: k-pixel sums (k = 2, 4, 6), means (k = 3).
    const bool rgb = channels == 3;
    sums_.assign(rgb && (k == 2 || k == 4 || k == 6) ? columns_.size() : 0, 0);
    means_.assign(rgb && k == 3 ? columns_.size() : 0, 0);
    const int area = k * k;
    mean_.resize(static_cast<std::size_t>(255) * area + 1);
    // OpenCV's rounding of the block sum s: half up for k = 2 (its 2 x 2 path), else
    // s times the float 1 / k^2 rounded half to even (for odd k the same as
    // (s + k^2 / 2) / k^2: no ties).
    const float inverse = 1.f / static_cast<float>(area);
    for (std::size_t s = 0; s < mean_.size(); ++s)
        mean_[s] = static_cast<std::uint8_t>(k == 2 ? (s + 2) / 4
                                                    : std::lrint(static_cast<float>(s) * inverse));
    return true;
}

namespace {

// One output row for a factor K known at compile time, three channels: the sums of K
// neighbouring pixels' column sums for every position (vectorised), then every K-th
// pixel's mean from the table. 1920 -> 320 px is K = 6.
template <int K>
void row_means_k3(const std::uint16_t* columns, int width, std::uint16_t* sums,
                  const std::uint8_t* mean, std::uint8_t* out) {
    const int n = width * 3 * K - 3 * (K - 1);
    for (int i = 0; i < n; ++i) {
        unsigned s = 0;
        for (int t = 0; t < K; ++t) s += columns[i + 3 * t];
        sums[i] = static_cast<std::uint16_t>(s);
    }
    for (int x = 0; x < width; ++x, sums += 3 * K, out += 3) {
        out[0] = mean[sums[0]];
        out[1] = mean[sums[1]];
        out[2] = mean[sums[2]];
    }
}

// k = 3, three channels (1920 -> 640 px, the gesture segmenter's reduction), without
// the table: for odd k the mean is (s + 4) / 9 (configure()), and for s + 4 <= 2299
// that is (s + 4) * 7282 >> 16 exactly (7282 = 2^16 / 9 + 2/9: the error stays below
// 2299 / (9 * 2^15) < 1/9), which vectorises (a 16-bit high multiply). Every position's
// mean first, then each pixel's three bytes (nine positions apart) in one 4-byte move;
// the lookups this replaces cost more than the 3x wider arithmetic.
ENDOTOWER_WIDE_VECTORS void row_means_3x3(const std::uint16_t* columns, int width,
                                          std::uint8_t* means, std::uint8_t* out) {
    const int n = width * 9 - 6;
    for (int i = 0; i < n; ++i) {
        const auto s = static_cast<std::uint16_t>(columns[i] + columns[i + 3] + columns[i + 6] + 4);
        means[i] = static_cast<std::uint8_t>((static_cast<std::uint32_t>(s) * 7282u) >> 16);
    }
    int x = 0;
    for (; x + 1 < width; ++x) std::memcpy(out + 3 * x, means + 9 * x, 4);  // the 4th: x + 1's
    std::memcpy(out + 3 * x, means + 9 * x, 3);
}

void row_means_any(const std::uint16_t* columns, int width, int k, int channels,
                   const std::uint8_t* mean, std::uint8_t* out) {
    for (int x = 0; x < width; ++x, columns += k * channels, out += channels)
        for (int c = 0; c < channels; ++c) {
            unsigned s = 0;
            for (int t = 0; t < k; ++t) s += columns[t * channels + c];
            out[c] = mean[s];
        }
}

}  // namespace

ENDOTOWER_WIDE_VECTORS void BlockMean::run(const std::uint8_t* src, std::size_t src_stride,
                                           std::uint8_t* dst, std::size_t dst_stride) {
    if (factor_ == 0) return;
    const int k = factor_;
    const std::size_t n = columns_.size();
    std::uint16_t* col = columns_.data();
    for (int y = 0; y < dst_height_; ++y, dst += dst_stride) {
        const std::uint8_t* row = src + static_cast<std::size_t>(y) * k * src_stride;
        if (k == 3) {  // one pass over the three rows, not three over the sums
            const std::uint8_t *r1 = row + src_stride, *r2 = r1 + src_stride;
            for (std::size_t i = 0; i < n; ++i)
                col[i] = static_cast<std::uint16_t>(row[i] + r1[i] + r2[i]);
        } else {
            for (std::size_t i = 0; i < n; ++i) col[i] = row[i];
            for (int j = 1; j < k; ++j) {
                row += src_stride;
                for (std::size_t i = 0; i < n; ++i)
                    col[i] = static_cast<std::uint16_t>(col[i] + row[i]);
            }
        }
        if (k == 3 && channels_ == 3)
            row_means_3x3(col, dst_width_, means_.data(), dst);
        else if (k == 6 && channels_ == 3)
            row_means_k3<6>(col, dst_width_, sums_.data(), mean_.data(), dst);
        else if (k == 4 && channels_ == 3)
            row_means_k3<4>(col, dst_width_, sums_.data(), mean_.data(), dst);
        else if (k == 2 && channels_ == 3)
            row_means_k3<2>(col, dst_width_, sums_.data(), mean_.data(), dst);
        else
            row_means_any(col, dst_width_, k, channels_, mean_.data(), dst);
    }
}

}  // namespace endotower::vision
