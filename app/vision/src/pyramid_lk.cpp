// LkPyramid and PyramidLk (see the header): float arithmetic, per-column accumulators so
// the window loops vectorise, fixed-size stack patches: no allocation after reserve().
#include "pyramid_lk.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>

#include "reflect_border.hpp"

namespace endotower::vision::detail {

namespace {

// Window rows are kCols floats, the columns past the window zero in the gradients: the
// loops run over whole vectors (and vectorise) whatever the window.
constexpr int kMaxWindow = 15;
constexpr int kCols = 16;
constexpr int kPatch = kCols + 2;  // a row of the window and a pixel each side (Scharr)
static_assert(LkPyramid::kBorder >= kPatch, "the border must hold a padded window row");

}  // namespace

void LkPyramid::reserve(int max_width, int max_height, const LkParams& p) {
    window_ = std::clamp(p.window | 1, 3, kMaxWindow);
    max_level_ = std::max(0, p.max_level);
    border_ = kBorder;
    planes_.assign(static_cast<std::size_t>(max_level_) + 1, Plane{});
    int w = std::max(1, max_width), h = std::max(1, max_height);
    for (Plane& q : planes_) {
        q.cap_w = w, q.cap_h = h;
        q.stride = w + 2 * border_;
        q.buf.assign(static_cast<std::size_t>(q.stride) * static_cast<std::size_t>(h + 2 * border_),
                     0.f);
        w = (w + 1) / 2, h = (h + 1) / 2;
    }
    row_.assign(static_cast<std::size_t>(max_width) + 2 * static_cast<std::size_t>(border_), 0.f);
    levels_ = 0;
}

float* LkPyramid::origin(Plane& p) const {
    return p.buf.data() + border_ * p.stride + border_;
}

float* LkPyramid::base(int width, int height) {
    if (planes_.empty() || width < 1 || height < 1 || width > planes_[0].cap_w ||
        height > planes_[0].cap_h)
        return nullptr;
    Plane& b = planes_[0];
    b.width = width, b.height = height;
    return origin(b);
}

LkPyramid::Level LkPyramid::level(int l) const {
    const Plane& p = planes_[static_cast<std::size_t>(l)];
    return {p.buf.data() + border_ * p.stride + border_, p.stride, p.width, p.height};
}

// Fills the border with the reflection (101) of the inside.
void LkPyramid::pad(Plane& p) const {
    float* o = origin(p);
    for (int y = 0; y < p.height; ++y) {
        float* r = o + y * p.stride;
        for (int x = 1; x <= border_; ++x) {
            r[-x] = r[reflect101(-x, p.width)];
            r[p.width - 1 + x] = r[reflect101(p.width - 1 + x, p.width)];
        }
    }
    const std::size_t row =
        static_cast<std::size_t>(p.width) + 2 * static_cast<std::size_t>(border_);
    for (int y = 1; y <= border_; ++y) {
        std::copy_n(o + reflect101(-y, p.height) * p.stride - border_, row,
                    o - y * p.stride - border_);
        std::copy_n(o + reflect101(p.height - 1 + y, p.height) * p.stride - border_, row,
                    o + (p.height - 1 + y) * p.stride - border_);
    }
}

void LkPyramid::build() {
    levels_ = 0;
    if (planes_.empty()) return;
    pad(planes_[0]);
    levels_ = 1;
    // [1 4 6 4 1] / 16 in each direction, at the even pixels (OpenCV's pyrDown).
    for (int l = 1; l <= max_level_; ++l) {
        Plane& src = planes_[static_cast<std::size_t>(l) - 1];
        Plane& dst = planes_[static_cast<std::size_t>(l)];
        const int w = (src.width + 1) / 2, h = (src.height + 1) / 2;
        if (w <= window_ || h <= window_) break;  // OpenCV's rule: larger than the window
        dst.width = w, dst.height = h;
        const float* s = origin(src);
        float* d = origin(dst);
        float* t = row_.data() + 2;  // t[-2 .. src.width + 1]
        for (int y = 0; y < h; ++y) {
            const float* r0 = s + (2 * y - 2) * src.stride;
            const std::ptrdiff_t st = src.stride;
            for (int x = -2; x < src.width + 2; ++x)
                t[x] = r0[x] + 4 * r0[x + st] + 6 * r0[x + 2 * st] + 4 * r0[x + 3 * st] +
                       r0[x + 4 * st];
            float* o = d + y * dst.stride;
            for (int x = 0; x < w; ++x) {
                const float* c = t + 2 * x;
                o[x] = (c[-2] + 4 * c[-1] + 6 * c[0] + 4 * c[1] + c[2]) * (1.f / 256);
            }
        }
        pad(dst);
        levels_ = l + 1;
    }
}

PyramidLk::PyramidLk(LkParams p) : p_(p) {
    p_.window = std::clamp(p_.window | 1, 3, kMaxWindow);
}

void PyramidLk::track(const LkPyramid& prev, const LkPyramid& next,
                      std::span<const cv::Point2f> prev_pts, std::span<cv::Point2f> next_pts,
                      std::span<std::uint8_t> status) const {
    const int win = p_.window, half = (win - 1) / 2;
    const int top = std::min({p_.max_level, prev.levels() - 1, next.levels() - 1});
    const auto eps2 = static_cast<float>(p_.epsilon * p_.epsilon);
    // OpenCV's units: its Scharr gradients are 32x ours, its sums scaled by 2^-20.
    const double eig_scale = 1.0 / (1024.0 * win * win);
    alignas(16) std::array<float, (kMaxWindow + 2) * kPatch> patch{};
    alignas(16) std::array<float, kMaxWindow * kCols> iv{}, ix{}, iy{};
    alignas(16) std::array<float, kCols> acc_x{}, acc_y{};
    for (std::size_t i = 0; i < prev_pts.size(); ++i) {
        status[i] = top >= 0 ? 1 : 0;
        cv::Point2f centre = prev_pts[i];  // of the window in `next`, at the level
        for (int l = top; l >= 0; --l) {
            const LkPyramid::Level a = prev.level(l), b = next.level(l);
            const float scale = 1.f / static_cast<float>(1 << l);
            const cv::Point2f p = prev_pts[i] * scale - cv::Point2f(half, half);
            centre = l == top ? prev_pts[i] * scale : centre * 2.f;
            const int px = static_cast<int>(std::floor(p.x)),
                      py = static_cast<int>(std::floor(p.y));
            if (px < -win || px >= a.width || py < -win || py >= a.height) {
                if (l == 0) status[i] = 0;
                continue;
            }
            // The previous window and a pixel around it at p's sub-pixel position.
            {
                const float fx = p.x - static_cast<float>(px), fy = p.y - static_cast<float>(py);
                const float w00 = (1 - fx) * (1 - fy), w01 = fx * (1 - fy), w10 = (1 - fx) * fy,
                            w11 = fx * fy;
                for (int r = 0; r < win + 2; ++r) {
                    const float* s0 = a.data + (py - 1 + r) * a.stride + (px - 1);
                    const float* s1 = s0 + a.stride;
                    float* o = patch.data() + r * kPatch;
                    for (int c = 0; c < kPatch; ++c)
                        o[c] = w00 * s0[c] + w01 * s0[c + 1] + w10 * s1[c] + w11 * s1[c + 1];
                }
            }
            double a11 = 0, a12 = 0, a22 = 0;
            for (int r = 0; r < win; ++r) {
                const float* u = patch.data() + r * kPatch + 1;
                const float* m = u + kPatch;
                const float* d = m + kPatch;
                float* vr = iv.data() + r * kCols;
                float* xr = ix.data() + r * kCols;
                float* yr = iy.data() + r * kCols;
                for (int c = 0; c < kCols; ++c) {
                    vr[c] = m[c];
                    xr[c] = (3 * (u[c + 1] - u[c - 1] + d[c + 1] - d[c - 1]) +
                             10 * (m[c + 1] - m[c - 1])) *
                            (1.f / 32);
                    yr[c] = (3 * (d[c - 1] - u[c - 1] + d[c + 1] - u[c + 1]) + 10 * (d[c] - u[c])) *
                            (1.f / 32);
                }
                for (int c = win; c < kCols; ++c) xr[c] = yr[c] = 0;
                for (int c = 0; c < win; ++c)
                    a11 += xr[c] * xr[c], a12 += xr[c] * yr[c], a22 += yr[c] * yr[c];
            }
            const double det = a11 * a22 - a12 * a12;
            const double min_eig =
                (a22 + a11 - std::sqrt((a11 - a22) * (a11 - a22) + 4 * a12 * a12)) / 2 * eig_scale;
            if (min_eig < p_.min_eigen || det < FLT_EPSILON * 1024.0 * 1024.0) {
                if (l == 0) status[i] = 0;
                continue;
            }
            const double inv = 1.0 / det;
            cv::Point2f q = centre - cv::Point2f(half, half), last(0, 0);
            for (int it = 0; it < p_.max_iterations; ++it) {
                const int qx = static_cast<int>(std::floor(q.x)),
                          qy = static_cast<int>(std::floor(q.y));
                if (qx < -win || qx >= b.width || qy < -win || qy >= b.height) {
                    if (l == 0) status[i] = 0;
                    break;
                }
                const float fx = q.x - static_cast<float>(qx), fy = q.y - static_cast<float>(qy);
                const float w00 = (1 - fx) * (1 - fy), w01 = fx * (1 - fy), w10 = (1 - fx) * fy,
                            w11 = fx * fy;
                acc_x.fill(0.f);
                acc_y.fill(0.f);
                for (int r = 0; r < win; ++r) {
                    const float* s0 = b.data + (qy + r) * b.stride + qx;
                    const float* s1 = s0 + b.stride;
                    const float* vr = iv.data() + r * kCols;
                    const float* xr = ix.data() + r * kCols;
                    const float* yr = iy.data() + r * kCols;
                    for (int c = 0; c < kCols; ++c) {
                        const float diff =
                            w00 * s0[c] + w01 * s0[c + 1] + w10 * s1[c] + w11 * s1[c + 1] - vr[c];
                        acc_x[static_cast<std::size_t>(c)] += diff * xr[c];
                        acc_y[static_cast<std::size_t>(c)] += diff * yr[c];
                    }
                }
                double b1 = 0, b2 = 0;
                for (int c = 0; c < kCols; ++c)
                    b1 += acc_x[static_cast<std::size_t>(c)],
                        b2 += acc_y[static_cast<std::size_t>(c)];
                const cv::Point2f delta(static_cast<float>((a12 * b2 - a22 * b1) * inv),
                                        static_cast<float>((a12 * b1 - a11 * b2) * inv));
                q += delta;
                centre = q + cv::Point2f(half, half);
                if (delta.dot(delta) <= eps2) break;
                if (it > 0 && std::abs(delta.x + last.x) < 0.01f &&
                    std::abs(delta.y + last.y) < 0.01f) {
                    centre -= delta * 0.5f;  // oscillating: the middle
                    break;
                }
                last = delta;
            }
        }
        next_pts[i] = centre;
    }
}

}  // namespace endotower::vision::detail
