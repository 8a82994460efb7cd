// AreaMean: cv::resize's INTER_AREA reduction without its per-call allocation
// (area_mean.hpp).
#include "endotower/vision/area_mean.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace endotower::vision {

namespace {

// The weights of one direction as OpenCV computes them (double cell bounds, float
// weights): output cell d covers input [d s, d s + s); a pixel cut by a border by
// more than 1e-3 counts with the part covered.
void area_weights(int in, int out, int channels, double scale, std::vector<AreaMean::Weight>& tab) {
    tab.clear();
    tab.reserve(static_cast<std::size_t>(in) * 2);
    for (int d = 0; d < out; ++d) {
        const double first = d * scale;
        const double last = first + scale;
        const double cell = std::min(scale, in - first);
        int s1 = static_cast<int>(std::ceil(first));
        int s2 = std::min(static_cast<int>(std::floor(last)), in - 1);
        s1 = std::min(s1, s2);
        if (s1 - first > 1e-3)
            tab.push_back(
                {d * channels, (s1 - 1) * channels, static_cast<float>((s1 - first) / cell)});
        for (int s = s1; s < s2; ++s)
            tab.push_back({d * channels, s * channels, static_cast<float>(1.0 / cell)});
        if (last - s2 > 1e-3)
            tab.push_back({d * channels, s2 * channels,
                           static_cast<float>(std::min(std::min(last - s2, 1.0), cell) / cell)});
    }
}

}  // namespace

bool AreaMean::configure(int src_width, int src_height, int dst_width, int dst_height,
                         int channels) {
    columns_.clear();
    rows_.clear();
    row_start_.clear();
    block_ = BlockMean{};
    src_width_ = src_width;
    src_height_ = src_height;
    if (src_width <= 0 || src_height <= 0 || dst_width <= 0 || dst_height <= 0 || channels <= 0)
        return false;
    // OpenCV's scale: the inverse of the inverse, so its last bit decides as there.
    const double scale_x = 1.0 / (static_cast<double>(dst_width) / src_width);
    const double scale_y = 1.0 / (static_cast<double>(dst_height) / src_height);
    if (scale_x < 1 || scale_y < 1) return false;  // OpenCV interpolates instead
    const bool integer = std::abs(scale_x - std::lround(scale_x)) < DBL_EPSILON &&
                         std::abs(scale_y - std::lround(scale_y)) < DBL_EPSILON;
    if (integer) return block_.configure(src_width, src_height, dst_width, dst_height, channels);
    channels_ = channels;
    area_weights(src_width, dst_width, channels, scale_x, columns_);
    area_weights(src_height, dst_height, 1, scale_y, rows_);
    row_start_.assign(static_cast<std::size_t>(dst_height) + 1, 0);
    for (std::size_t j = 0; j < rows_.size(); ++j)
        if (j == 0 || rows_[j].dst != rows_[j - 1].dst)
            row_start_[rows_[j].dst] = static_cast<int>(j);
    row_start_[dst_height] = static_cast<int>(rows_.size());
    line_.assign(static_cast<std::size_t>(dst_width) * channels, 0.f);
    sum_.assign(line_.size(), 0.f);
    return true;
}

void AreaMean::run(const std::uint8_t* src, std::size_t src_stride, std::uint8_t* dst,
                   std::size_t dst_stride) {
    if (block_.ready()) {
        block_.run(src, src_stride, dst, dst_stride);
        return;
    }
    if (row_start_.empty()) return;
    const int n = static_cast<int>(line_.size());
    const int dst_height = static_cast<int>(row_start_.size()) - 1;
    float* line = line_.data();
    float* sum = sum_.data();
    int line_row = -1;  // the input row `line` holds: a row cut by a cell border is
                        // used by two output rows, its column sums computed once
    for (int y = 0; y < dst_height; ++y, dst += dst_stride) {
        for (int j = row_start_[y]; j < row_start_[y + 1]; ++j) {
            if (rows_[j].src != line_row) {
                line_row = rows_[j].src;
                const std::uint8_t* s = src + static_cast<std::size_t>(line_row) * src_stride;
                column_sums(s, line);
            }
            const float beta = rows_[j].alpha;
            if (j == row_start_[y])
                for (int i = 0; i < n; ++i) sum[i] = beta * line[i];
            else
                for (int i = 0; i < n; ++i) sum[i] += beta * line[i];
        }
        for (int i = 0; i < n; ++i)
            dst[i] = static_cast<std::uint8_t>(std::clamp(std::lrint(sum[i]), 0L, 255L));
    }
}

void AreaMean::column_sums(const std::uint8_t* s, float* line) const {
    std::fill(line, line + line_.size(), 0.f);
    // The same sums in the same order as OpenCV (float; fused multiply-adds where
    // OpenCV's build has them: this file is built with -ffp-contract=fast), so the same
    // bytes.
    if (channels_ == 3) {
        for (const Weight& w : columns_) {
            line[w.dst] += s[w.src] * w.alpha;
            line[w.dst + 1] += s[w.src + 1] * w.alpha;
            line[w.dst + 2] += s[w.src + 2] * w.alpha;
        }
        return;
    }
    for (const Weight& w : columns_)
        for (int c = 0; c < channels_; ++c) line[w.dst + c] += s[w.src + c] * w.alpha;
}

}  // namespace endotower::vision
