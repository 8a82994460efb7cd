// MaskOps: allocation-free binary-image operations equal to OpenCV's (mask_ops.hpp).
#include "endotower/vision/mask_ops.hpp"

#include <algorithm>
#include <climits>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "wide_vectors.hpp"

namespace endotower::vision {

namespace {

// cv::borderInterpolate with BORDER_REFLECT_101.
int reflect101(int p, int n) {
    if (n == 1) return 0;
    while (p < 0 || p >= n) p = p < 0 ? -p : 2 * (n - 1) - p;
    return p;
}

template <bool kErode>
void combine(std::uint8_t* o, const std::uint8_t* s, int w) {
    for (int x = 0; x < w; ++x) o[x] = kErode ? std::min(o[x], s[x]) : std::max(o[x], s[x]);
}

// The first nonzero byte of r[x..w), or w.
int next_set(const std::uint8_t* r, int x, int w) {
    for (; x + 8 <= w; x += 8) {
        std::uint64_t word;
        std::memcpy(&word, r + x, 8);
        if (word != 0) break;
    }
    while (x < w && r[x] == 0) ++x;
    return x;
}

// The first zero byte of r[x..w), or w (a mask's set bytes are 255: eight at a time).
int next_clear(const std::uint8_t* r, int x, int w) {
    for (; x + 8 <= w; x += 8) {
        std::uint64_t word;
        std::memcpy(&word, r + x, 8);
        if (word != ~std::uint64_t{0}) break;
    }
    while (x < w && r[x] != 0) ++x;
    return x;
}

// cv::distanceTransform's 3x3 L2 weights, CV_FLT_TO_FIX(0.955f / 1.3693f, 16).
constexpr std::uint32_t kHv = 62587, kDiag = 89738, kFar = INT_MAX >> 2;

}  // namespace

void MaskOps::configure(int width, int height) {
    width_ = std::max(1, width);
    height_ = std::max(1, height);
    const auto plane = static_cast<std::size_t>(width_) * height_;
    columns_.assign(width_, 0);
    padded_sums_.assign(width_ + 8, 0);
    box_.assign(width_, 0);
    padded_.assign(width_ + 16, 0);
    spans_.assign(plane * 4, 0);  // up to four distinct half-widths per element
    tmp_.assign(plane, 0);
    rows_.assign(plane, 0);
    // label(): at most ceil(w / 2) runs a row, and as many provisional labels; the
    // components (8-connected) at most ceil(w / 2) x ceil(h / 2).
    const std::size_t runs = static_cast<std::size_t>((width_ + 1) / 2) * height_;
    runs_.assign(runs, Run{});
    parent_.assign(runs + 1, 0);
    components_.reserve(static_cast<std::size_t>((width_ + 1) / 2) * ((height_ + 1) / 2) + 1);
    chamfer_.assign(static_cast<std::size_t>(width_ + 2) * (height_ + 2), 0);
}

ENDOTOWER_WIDE_VECTORS LitMoments MaskOps::lit_field(BytePlane g, int threshold, BytePlane lit) {
    constexpr int kR = 4, kArea = (2 * kR + 1) * (2 * kR + 1);
    const int w = g.width, h = g.height;
    std::uint32_t* col = columns_.data();
    std::fill(col, col + w, 0u);
    for (int dy = -kR; dy <= kR; ++dy) {
        const std::uint8_t* r = g.row(reflect101(dy, h));
        for (int x = 0; x < w; ++x) col[x] += r[x];
    }
    std::int64_t m00 = 0, m10 = 0, m01 = 0;
    std::uint32_t* ps = padded_sums_.data();
    const std::int64_t at_least = std::int64_t{kArea} * (threshold + 1) - kArea / 2;
    const auto limit =
        static_cast<std::uint32_t>(std::clamp<std::int64_t>(at_least, 0, UINT32_MAX));
    for (int y = 0; y < h; ++y) {
        if (y > 0) {
            const std::uint8_t* add = g.row(reflect101(y + kR, h));
            const std::uint8_t* sub = g.row(reflect101(y - 1 - kR, h));
            for (int x = 0; x < w; ++x) col[x] = col[x] + add[x] - sub[x];
        }
        std::memcpy(ps + kR, col, sizeof(std::uint32_t) * w);
        for (int i = 0; i < kR; ++i) {
            ps[i] = col[reflect101(i - kR, w)];
            ps[w + kR + i] = col[reflect101(w + i, w)];
        }
        // The 9-wide sums (vectorised), then mean > threshold without the division:
        // (s + 40) / 81 > t  <=>  s >= 81 (t + 1) - 40.
        std::uint32_t* box = box_.data();
        for (int x = 0; x < w; ++x)
            box[x] = ps[x] + ps[x + 1] + ps[x + 2] + ps[x + 3] + ps[x + 4] + ps[x + 5] + ps[x + 6] +
                     ps[x + 7] + ps[x + 8];
        std::uint8_t* out = lit.row(y);
        std::int32_t count = 0, xs = 0;
        for (int x = 0; x < w; ++x) {
            const std::int32_t on = box[x] >= limit ? 1 : 0;
            out[x] = static_cast<std::uint8_t>(on * 255);
            count += on;
            xs += on * x;
        }
        m00 += count;
        m10 += xs;
        m01 += count * y;
    }
    return {static_cast<double>(m00), static_cast<double>(m10), static_cast<double>(m01)};
}

int MaskOps::ellipse_rows(int r, std::array<int, 15>& rows) {
    r = std::clamp(r, 0, 7);
    const int m = 2 * r + 1;
    const cv::Mat e = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(m, m));
    for (int y = 0; y < m; ++y) {  // each row of the ellipse is centred on column r
        const std::uint8_t* row = e.ptr<std::uint8_t>(y);
        int first = 0;
        while (first < m && row[first] == 0) ++first;
        rows[static_cast<std::size_t>(y)] = first < m ? r - first : -1;
    }
    return m;
}

ENDOTOWER_WIDE_VECTORS void MaskOps::morph(BytePlane in, BytePlane out,
                                           std::span<const int> half_widths, bool erode) {
    const int w = in.width, h = in.height, c = static_cast<int>(half_widths.size()) / 2;
    const std::uint8_t pad = erode ? 255 : 0;
    const auto plane = static_cast<std::size_t>(w) * h;
    // One plane of horizontal min (max) per distinct half-width.
    int widths[4], planes = 0;
    for (int hw : half_widths)
        if (hw >= 0 && std::find(widths, widths + planes, hw) == widths + planes && planes < 4)
            widths[planes++] = hw;
    std::uint8_t* row_pad = padded_.data();
    for (int k = 0; k < planes; ++k) {
        const int hw = std::min(widths[k], 7);  // padded_ has 8 bytes a side
        for (int y = 0; y < h; ++y) {
            std::memset(row_pad, pad, hw);
            std::memcpy(row_pad + hw, in.row(y), w);
            std::memset(row_pad + hw + w, pad, hw);
            std::uint8_t* o = spans_.data() + k * plane + static_cast<std::size_t>(y) * w;
            std::memcpy(o, row_pad, w);
            for (int d = 1; d <= 2 * hw; ++d)
                erode ? combine<true>(o, row_pad + d, w) : combine<false>(o, row_pad + d, w);
        }
    }
    for (int y = 0; y < h; ++y) {
        std::uint8_t* o = out.row(y);
        std::memset(o, pad, w);
        for (int dy = -c; dy <= c; ++dy) {
            const int hw = half_widths[dy + c], yy = y + dy;
            if (hw < 0 || yy < 0 || yy >= h) continue;  // outside the image: ignored
            const int k = static_cast<int>(std::find(widths, widths + planes, hw) - widths);
            if (k == planes) continue;
            const std::uint8_t* s = spans_.data() + k * plane + static_cast<std::size_t>(yy) * w;
            erode ? combine<true>(o, s, w) : combine<false>(o, s, w);
        }
    }
}

void MaskOps::open3(BytePlane in, BytePlane out) {
    static constexpr int kSquare[3] = {1, 1, 1};
    const BytePlane tmp{tmp_.data(), in.width, in.height, static_cast<std::size_t>(in.width)};
    morph(in, tmp, kSquare, true);
    morph(tmp, out, kSquare, false);
}

ENDOTOWER_WIDE_VECTORS void MaskOps::smooth_at_least(BytePlane in, int threshold,
                                                     BytePlane and_mask, BytePlane out,
                                                     BytePlane smoothed) {
    // Q8.8 taps; the row pass stays in 16 bits (255 x 256), the column pass in 32.
    constexpr std::uint32_t k0 = 22, k1 = 62, k2 = 88;
    const int w = in.width, h = in.height;
    std::uint8_t* p = padded_.data();
    for (int y = 0; y < h; ++y) {
        const std::uint8_t* r = in.row(y);
        std::memcpy(p + 2, r, w);
        p[0] = r[reflect101(-2, w)], p[1] = r[reflect101(-1, w)];
        p[w + 2] = r[reflect101(w, w)], p[w + 3] = r[reflect101(w + 1, w)];
        std::uint16_t* o = rows_.data() + static_cast<std::size_t>(y) * w;
        for (int x = 0; x < w; ++x)
            o[x] = static_cast<std::uint16_t>(k0 * (p[x] + p[x + 4]) + k1 * (p[x + 1] + p[x + 3]) +
                                              k2 * p[x + 2]);
    }
    // (sum + 2^15) >> 16 >= threshold  <=>  sum >= threshold 2^16 - 2^15.
    const std::int64_t at_least = std::int64_t{threshold} * 65536 - 32768;
    const std::uint32_t limit =
        at_least <= 0 ? 0u
                      : static_cast<std::uint32_t>(std::min<std::int64_t>(at_least, UINT32_MAX));
    for (int y = 0; y < h; ++y) {
        const std::uint16_t* a = rows_.data() + static_cast<std::size_t>(reflect101(y - 2, h)) * w;
        const std::uint16_t* b = rows_.data() + static_cast<std::size_t>(reflect101(y - 1, h)) * w;
        const std::uint16_t* c = rows_.data() + static_cast<std::size_t>(y) * w;
        const std::uint16_t* d = rows_.data() + static_cast<std::size_t>(reflect101(y + 1, h)) * w;
        const std::uint16_t* e = rows_.data() + static_cast<std::size_t>(reflect101(y + 2, h)) * w;
        const std::uint8_t* m = and_mask.row(y);
        std::uint8_t* o = out.row(y);
        for (int x = 0; x < w; ++x) {
            const std::uint32_t v = k0 * (a[x] + e[x]) + k1 * (b[x] + d[x]) + k2 * c[x];
            o[x] = static_cast<std::uint8_t>((v >= limit ? 255 : 0) & (m[x] != 0 ? 255 : 0));
        }
        if (smoothed.data != nullptr) {
            std::uint8_t* q = smoothed.row(y);
            for (int x = 0; x < w; ++x)
                q[x] = static_cast<std::uint8_t>(
                    (k0 * (a[x] + e[x]) + k1 * (b[x] + d[x]) + k2 * c[x] + 32768u) >> 16);
        }
    }
}

int MaskOps::label(BytePlane m, std::int32_t* labels) {
    return label(m, labels, static_cast<std::size_t>(m.width), 0, 0);
}

int MaskOps::label(BytePlane m, std::int32_t* labels, std::size_t stride, int x0, int y0) {
    // Runs of set pixels, not pixels: a run's provisional label is its number + 1 in
    // raster order, and it joins every run of the row above that it touches
    // (8-connected: overlapping or meeting at a corner). A union keeps the smaller label,
    // so a set's root is its first run, and the final labels count the sets in the
    // raster order of their first pixels: cv::connectedComponents' labels.
    const int w = m.width, h = m.height;
    Run* runs = runs_.data();
    std::int32_t* parent = parent_.data();
    auto root = [parent](std::int32_t a) {
        while (parent[a] != a) a = parent[a] = parent[parent[a]];
        return a;
    };
    std::int32_t count = 0;
    std::int32_t above = 0, above_end = 0;  // the row above's runs
    for (int y = 0; y < h; ++y) {
        const std::uint8_t* r = m.row(y);
        const std::int32_t first = count;
        std::int32_t j = above;
        for (int x = next_set(r, 0, w); x < w;) {
            const int end = next_clear(r, x + 1, w);
            const std::int32_t id = ++count;
            runs[id - 1] = {y, x, end};
            parent[id] = id;
            std::int32_t lab = id;
            while (j < above_end && runs[j].end < x) ++j;  // ends left of x - 1
            for (std::int32_t k = j; k < above_end && runs[k].start <= end; ++k) {
                const std::int32_t a = root(lab), b = root(k + 1);
                lab = std::min(a, b);
                parent[std::max(a, b)] = lab;
            }
            x = next_set(r, end, w);
        }
        above = first, above_end = count;
    }
    std::int32_t n = 1;
    for (std::int32_t i = 1; i <= count; ++i) parent[i] = parent[i] == i ? n++ : parent[parent[i]];
    components_.assign(static_cast<std::size_t>(n), Component{w, h, -1, -1, 0});
    if (stride == static_cast<std::size_t>(w))
        std::memset(labels, 0, sizeof(std::int32_t) * static_cast<std::size_t>(w) * h);
    else
        for (int y = 0; y < h; ++y) std::fill_n(labels + y * stride, w, 0);
    for (std::int32_t i = 0; i < count; ++i) {
        const Run& run = runs[i];
        const std::int32_t lab = parent[i + 1];
        std::fill(labels + static_cast<std::size_t>(run.y) * stride + run.start,
                  labels + static_cast<std::size_t>(run.y) * stride + run.end, lab);
        Component& c = components_[lab];
        c.area += run.end - run.start;
        c.left = std::min(c.left, run.start), c.right = std::max(c.right, run.end - 1);
        c.top = std::min(c.top, run.y), c.bottom = std::max(c.bottom, run.y);
    }
    if (x0 != 0 || y0 != 0)
        for (std::size_t i = 1; i < components_.size(); ++i) {
            Component& c = components_[i];
            c.left += x0, c.right += x0, c.top += y0, c.bottom += y0;
        }
    return n;
}

void MaskOps::configure_chamfer(int width, int height) {
    width_ = std::max(1, width);
    height_ = std::max(1, height);
    chamfer_.assign(static_cast<std::size_t>(width_ + 2) * (height_ + 2), 0);
}

void MaskOps::chamfer(BytePlane m, int x0, int y0, int x1, int y1, std::uint32_t* out) {
    const int ww = x1 - x0, wh = y1 - y0, s = ww + 2;
    std::uint32_t* t = chamfer_.data();
    std::fill(t, t + static_cast<std::size_t>(s) * (wh + 2), kFar);
    for (int y = 0; y < wh; ++y) {
        const std::uint8_t* r = m.row(y0 + y) + x0;
        std::uint32_t* c = t + static_cast<std::size_t>(y + 1) * s + 1;
        for (int x = 0; x < ww; ++x)
            c[x] = r[x] == 0 ? 0
                             : std::min({c[x - s - 1] + kDiag, c[x - s] + kHv, c[x - s + 1] + kDiag,
                                         c[x - 1] + kHv});
    }
    for (int y = wh - 1; y >= 0; --y) {
        std::uint32_t* c = t + static_cast<std::size_t>(y + 1) * s + 1;
        std::uint32_t* o = out + static_cast<std::size_t>(y) * ww;
        for (int x = ww - 1; x >= 0; --x) {
            std::uint32_t d = c[x];
            if (d > kHv)
                c[x] = d = std::min({d, c[x + s + 1] + kDiag, c[x + s] + kHv, c[x + s - 1] + kDiag,
                                     c[x + 1] + kHv});
            o[x] = d;
        }
    }
}

}  // namespace endotower::vision
