// HighPassWindow (see the header): separable passes over buffers sized in reserve().
#include "high_pass_window.hpp"

#include <algorithm>
#include <cmath>

#include "reflect_border.hpp"

namespace endotower::vision::detail {

namespace {

// (R 4899 + G 9617 + B 1868 + 2^13) >> 14, OpenCV's 8-bit grey; channel offsets as
// template arguments so the loop vectorises.
template <int C, int R, int G, int B>
void grey_pixels(const std::uint8_t* p, int n, float* out) {
    for (int x = 0; x < n; ++x)
        out[x] = static_cast<float>(
            (p[C * x + R] * 4899 + p[C * x + G] * 9617 + p[C * x + B] * 1868 + (1 << 13)) >> 14);
}

int round_size(double v) {
    return std::max(1, static_cast<int>(std::lrint(v)));  // cv::resize's cvRound
}

}  // namespace

void HighPassWindow::reserve(int width, int height, double s) {
    s_ = std::clamp(s, 1e-3, 1.0);
    max_w_ = std::max(1, width), max_h_ = std::max(1, height);
    const cv::Size d = scaled({max_w_, max_h_});
    // An area cell holds at most 1/s + 2 taps: all of them fit in w + 2 dw (+ slack).
    xtab_.assign(static_cast<std::size_t>(max_w_) + 2 * static_cast<std::size_t>(d.width) + 8,
                 Tap{});
    ytab_.assign(static_cast<std::size_t>(max_h_) + 2 * static_cast<std::size_t>(d.height) + 8,
                 Tap{});
    grey_.assign(2 * static_cast<std::size_t>(max_w_), 0.f);
    const double k = std::round(1.0 / s_);
    factor_ = s_ < 1.0 && std::abs(1.0 / s_ - k) < 1e-9 ? static_cast<int>(k) : 0;
    reduced_.assign(static_cast<std::size_t>(d.width), 0.f);
    area_stride_ = d.width + 2 * radius_;
    area_.assign(
        static_cast<std::size_t>(area_stride_) * static_cast<std::size_t>(d.height + 2 * radius_),
        0.f);
    sums_.assign(
        static_cast<std::size_t>(d.width) * static_cast<std::size_t>(d.height + 2 * radius_), 0.f);
}

cv::Size HighPassWindow::scaled(cv::Size roi) const {
    if (s_ >= 1.0) return roi;
    return {round_size(roi.width * s_), round_size(roi.height * s_)};
}

// OpenCV's area table (computeResizeAreaTab): for each destination pixel, the source
// pixels its cell covers and the fraction of the cell each contributes.
int HighPassWindow::area_table(int src_size, int dst_size, std::vector<Tap>& tab) const {
    const double scale = 1.0 / s_;
    std::size_t k = 0;
    const auto add = [&](int d, int s, double w) {
        if (k < tab.size()) tab[k++] = {d, s, static_cast<float>(w)};
    };
    for (int dx = 0; dx < dst_size; ++dx) {
        const double f1 = dx * scale, f2 = f1 + scale;
        const double cell = std::min(scale, src_size - f1);
        int s2 = std::min(static_cast<int>(std::floor(f2)), src_size - 1);
        const int s1 = std::min(static_cast<int>(std::ceil(f1)), s2);
        if (s1 - f1 > 1e-3) add(dx, s1 - 1, (s1 - f1) / cell);
        for (int sx = s1; sx < s2; ++sx) add(dx, sx, 1.0 / cell);
        if (f2 - s2 > 1e-3) add(dx, s2, std::min(std::min(f2 - s2, 1.0), cell) / cell);
    }
    return static_cast<int>(k);
}

// Grey of `width` pixels of row y from x0.
void HighPassWindow::grey_row(const hal::Frame& f, int y, int x0, int width, float* out) const {
    const std::uint8_t* row = f.data + static_cast<std::ptrdiff_t>(y) * f.format.stride;
    switch (f.format.pixel_format) {
        case hal::PixelFormat::kBgr24:
            grey_pixels<3, 2, 1, 0>(row + 3 * x0, width, out);
            break;
        case hal::PixelFormat::kRgb24:
            grey_pixels<3, 0, 1, 2>(row + 3 * x0, width, out);
            break;
        case hal::PixelFormat::kBgra32:
            grey_pixels<4, 2, 1, 0>(row + 4 * x0, width, out);
            break;
        default:
            for (int x = 0; x < width; ++x) out[x] = row[x0 + x];
            break;
    }
}

// Area reduction by an integer factor k (1/s): each destination pixel the mean of its
// k x k cell, a cell cut by the window's edge the mean of the pixels it holds (as the
// table path's clipped cells).
void HighPassWindow::reduce_by(int k, const hal::Frame& f, cv::Rect roi, cv::Size d, float* area) {
    float* sum = grey_.data() + roi.width;  // a second row of the same size
    for (int y = 0; y < d.height; ++y) {
        const int y0 = k * y, rows = std::min(k, roi.height - y0);
        std::fill_n(sum, roi.width, 0.f);
        for (int j = 0; j < rows; ++j) {
            grey_row(f, roi.y + y0 + j, roi.x, roi.width, grey_.data());
            for (int x = 0; x < roi.width; ++x) sum[x] += grey_[static_cast<std::size_t>(x)];
        }
        float* o = area + y * area_stride_;
        const int full = std::min(d.width, roi.width / k);
        const float inv = 1.f / static_cast<float>(k * rows);
        for (int x = 0; x < full; ++x) {
            float v = 0;
            for (int i = 0; i < k; ++i) v += sum[k * x + i];
            o[x] = v * inv;
        }
        for (int x = full; x < d.width; ++x) {
            const int cols = std::max(1, std::min(k, roi.width - k * x));
            float v = 0;
            for (int i = 0; i < cols; ++i) v += sum[std::min(k * x + i, roi.width - 1)];
            o[x] = v / static_cast<float>(cols * rows);
        }
    }
}

bool HighPassWindow::build(const hal::Frame& f, cv::Rect roi, LkPyramid& pyr) {
    using hal::PixelFormat;
    const PixelFormat pf = f.format.pixel_format;
    if (f.data == nullptr || (pf != PixelFormat::kBgr24 && pf != PixelFormat::kRgb24 &&
                              pf != PixelFormat::kBgra32 && pf != PixelFormat::kGray8))
        return false;
    if (f.format.width > max_w_ || f.format.height > max_h_ || roi.empty() ||
        (roi & cv::Rect(0, 0, f.format.width, f.format.height)) != roi)
        return false;
    const cv::Size d = scaled(roi.size());
    const int r = radius_;
    float* area = area_.data() + r * area_stride_ + r;  // pixel (0, 0)
    if (s_ >= 1.0) {
        for (int y = 0; y < d.height; ++y)
            grey_row(f, roi.y + y, roi.x, d.width, area + y * area_stride_);
    } else if (factor_ > 1) {
        reduce_by(factor_, f, roi, d, area);
    } else {
        for (int y = 0; y < d.height; ++y) std::fill_n(area + y * area_stride_, d.width, 0.f);
        const int nx = area_table(roi.width, d.width, xtab_);
        const int ny = area_table(roi.height, d.height, ytab_);
        int last = -1;
        for (int k = 0; k < ny; ++k) {
            const Tap ty = ytab_[static_cast<std::size_t>(k)];
            if (ty.src != last) {
                grey_row(f, roi.y + ty.src, roi.x, roi.width, grey_.data());
                std::fill(reduced_.begin(), reduced_.begin() + d.width, 0.f);
                for (int j = 0; j < nx; ++j) {
                    const Tap tx = xtab_[static_cast<std::size_t>(j)];
                    reduced_[static_cast<std::size_t>(tx.dst)] +=
                        grey_[static_cast<std::size_t>(tx.src)] * tx.weight;
                }
                last = ty.src;
            }
            float* o = area + ty.dst * area_stride_;
            for (int x = 0; x < d.width; ++x)
                o[x] += ty.weight * reduced_[static_cast<std::size_t>(x)];
        }
    }
    // The border the box needs, reflected; then the box's row sums over every padded row.
    for (int y = 0; y < d.height; ++y) {
        float* o = area + y * area_stride_;
        for (int x = 1; x <= r; ++x) {
            o[-x] = o[reflect101(-x, d.width)];
            o[d.width - 1 + x] = o[reflect101(d.width - 1 + x, d.width)];
        }
    }
    const auto row_len = static_cast<std::size_t>(d.width) + 2 * static_cast<std::size_t>(r);
    for (int y = 1; y <= r; ++y) {
        std::copy_n(area + reflect101(-y, d.height) * area_stride_ - r, row_len,
                    area - y * area_stride_ - r);
        std::copy_n(area + reflect101(d.height - 1 + y, d.height) * area_stride_ - r, row_len,
                    area + (d.height - 1 + y) * area_stride_ - r);
    }
    // Running sums (float: their drift over a window is below 1e-3 grey levels), four
    // rows at a time: four independent chains of additions keep the adder busy.
    const auto sums_row = [&](int y) {
        return sums_.data() + static_cast<std::ptrdiff_t>(y + r) * d.width;
    };
    int y = -r;
    for (; y + 4 <= d.height + r; y += 4) {
        const float* a[4];
        float* s[4];
        float run[4] = {0, 0, 0, 0};
        for (int i = 0; i < 4; ++i) {
            a[i] = area + (y + i) * area_stride_;
            s[i] = sums_row(y + i);
            for (int k = -r; k <= r; ++k) run[i] += a[i][k];
            s[i][0] = run[i];
        }
        for (int x = 1; x < d.width; ++x)
            for (int i = 0; i < 4; ++i) s[i][x] = run[i] += a[i][x + r] - a[i][x - r - 1];
    }
    for (; y < d.height + r; ++y) {
        const float* a = area + y * area_stride_;
        float* s = sums_row(y);
        float run = 0;
        for (int k = -r; k <= r; ++k) run += a[k];
        s[0] = run;
        for (int x = 1; x < d.width; ++x) s[x] = run += a[x + r] - a[x - r - 1];
    }
    float* base = pyr.base(d.width, d.height);
    if (base == nullptr) return false;
    const std::ptrdiff_t stride = pyr.level(0).stride;
    const float inv = 1.f / static_cast<float>((2 * r + 1) * (2 * r + 1));
    float* acc = reduced_.data();
    std::fill_n(acc, d.width, 0.f);
    for (int k = 0; k < 2 * r; ++k) {
        const float* s = sums_.data() + static_cast<std::ptrdiff_t>(k) * d.width;
        for (int x = 0; x < d.width; ++x) acc[x] += s[x];
    }
    for (int y = 0; y < d.height; ++y) {
        const float* in = sums_.data() + static_cast<std::ptrdiff_t>(y + 2 * r) * d.width;
        for (int x = 0; x < d.width; ++x) acc[x] += in[x];
        const float* a = area + y * area_stride_;
        float* o = base + y * stride;
        for (int x = 0; x < d.width; ++x) o[x] = a[x] - acc[x] * inv;
        const float* out = sums_.data() + static_cast<std::ptrdiff_t>(y) * d.width;
        for (int x = 0; x < d.width; ++x) acc[x] -= out[x];
    }
    pyr.build();
    return true;
}

}  // namespace endotower::vision::detail
