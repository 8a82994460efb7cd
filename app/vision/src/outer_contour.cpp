// ContourTracer: outer borders and convex hulls as OpenCV traces them (outer_contour.hpp).
#include "endotower/vision/outer_contour.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace endotower::vision {

namespace {

// Chain codes 0..7 counter-clockwise from +x (y down), as OpenCV's border following.
constexpr int kDx[8] = {1, 1, 0, -1, -1, -1, 0, 1};
constexpr int kDy[8] = {0, -1, -1, -1, 0, 1, 1, 1};

std::int64_t cross(IntPoint o, IntPoint a, IntPoint b) {
    return std::int64_t{a.x - o.x} * (b.y - o.y) - std::int64_t{a.y - o.y} * (b.x - o.x);
}

// The first cell of p[j..end] that is not background (0), or end + 1: eight at a time.
int zeros_to(const std::int8_t* p, int j, int end) {
    for (; j + 8 <= end + 1; j += 8) {
        std::uint64_t word;
        std::memcpy(&word, p + j, 8);
        if (word != 0) break;
    }
    while (j <= end && p[j] == 0) ++j;
    return j;
}

// The first background cell of p[j..end], or end + 1.
int set_to(const std::int8_t* p, int j, int end) {
    while (j <= end && p[j] != 0) ++j;
    return j;
}

}  // namespace

void ContourTracer::reserve(int width, int height) {
    width_ = std::max(1, width);
    height_ = std::max(1, height);
    const std::size_t cells = static_cast<std::size_t>(width_ + 2) * (height_ + 2);
    image_.assign(cells, 0);
    stack_.reserve(2 * cells);  // holes(): a run's first cell, from the row above and below
    // A border visits each pixel at most four times (once per side).
    for (auto* v : {&contour_, &best_, &sorted_, &hull_}) v->reserve(4 * cells + 8);
}

std::span<const IntPoint> ContourTracer::largest(const std::uint8_t* mask, int width, int height,
                                                 std::size_t stride, double& area) {
    area = 0;
    best_.clear();
    last_width_ = last_height_ = 0;
    if (mask == nullptr || width <= 0 || height <= 0 || width > width_ || height > height_)
        return {};
    last_width_ = width;
    last_height_ = height;
    const int s = width + 2;
    std::int8_t* img = image_.data();
    std::fill(img, img + static_cast<std::size_t>(s) * (height + 2), std::int8_t{0});
    for (int y = 0; y < height; ++y) {
        const std::uint8_t* r = mask + static_cast<std::size_t>(y) * stride;
        std::int8_t* o = img + static_cast<std::size_t>(y + 1) * s + 1;
        for (int x = 0; x < width; ++x) o[x] = r[x] != 0 ? 1 : 0;
    }
    int deltas[16];
    for (int k = 0; k < 16; ++k) deltas[k] = kDx[k & 7] + kDy[k & 7] * s;
    for (int y = 1; y <= height; ++y)
        for (int x = 1; x <= width; ++x) {
            const int i0 = y * s + x;
            if (img[i0] != 1 || img[i0 - 1] != 0) continue;  // not a new blob's first pixel
            // Border following (cv::findContours' icvFetchContour, outer border).
            contour_.clear();
            IntPoint pt{x, y};
            int dir = 4, i1 = i0;
            do {
                dir = (dir - 1) & 7;
                i1 = i0 + deltas[dir];
            } while (img[i1] == 0 && dir != 4);
            if (dir == 4) {
                contour_.push_back(pt);  // a single pixel
            } else {
                int i3 = i0, prev = dir ^ 4;
                for (;;) {
                    int i4 = i3;
                    dir = std::min(dir, 15);
                    while (dir < 15) {
                        i4 = i3 + deltas[++dir];
                        if (img[i4] != 0) break;
                    }
                    dir &= 7;
                    if (dir != prev) {
                        contour_.push_back(pt);
                        prev = dir;
                    }
                    pt.x += kDx[dir];
                    pt.y += kDy[dir];
                    if (i4 == i0 && i3 == i1) break;
                    i3 = i4;
                    dir = (dir + 4) & 7;
                }
            }
            // Mark the whole blob done (8-connected fill), so it is traced once.
            stack_.clear();
            stack_.push_back(i0);
            img[i0] = 2;
            while (!stack_.empty()) {
                const int i = stack_.back();
                stack_.pop_back();
                for (int k = 0; k < 8; ++k)
                    if (img[i + deltas[k]] == 1)
                        img[i + deltas[k]] = 2, stack_.push_back(i + deltas[k]);
            }
            const double a = polygon_area(contour_);
            if (contour_.size() >= 3 && a > 0 && a >= area) {
                area = a;
                best_.assign(contour_.begin(), contour_.end());
            }
        }
    return best_;
}

void ContourTracer::holes(int& largest, int& second) {
    largest = second = 0;
    if (last_width_ <= 0) return;
    const int s = last_width_ + 2, rows = last_height_ + 2;
    std::int8_t* img = image_.data();
    // 4-connected background fill from `seed` (marking it 3), a row run at a time (the
    // stack holds the runs' first cells, not every pixel); returns its pixel count.
    auto fill = [&](int seed) {
        int count = 0;
        stack_.clear();
        stack_.push_back(seed);
        while (!stack_.empty()) {
            const int i = stack_.back();
            stack_.pop_back();
            if (img[i] != 0) continue;  // pushed twice, filled since
            const int y = i / s, row = y * s;
            int l = i;
            while (l > row && img[l - 1] == 0) --l;
            const int r = zeros_to(img, i, row + s - 1) - 1;
            std::fill(img + l, img + r + 1, std::int8_t{3});
            count += r - l + 1;
            for (const int dy : {-1, 1}) {  // each run of background above and below l..r
                if (y + dy < 0 || y + dy >= rows) continue;
                const std::int8_t* q = img + dy * s;
                for (int j = l; (j = set_to(q, j, r)) <= r; j = zeros_to(q, j, r))
                    stack_.push_back(j + dy * s);
            }
        }
        return count;
    };
    fill(0);  // the zero border: everything outside
    const int n = s * rows;
    for (int i = 0; i < n; ++i)
        if (img[i] == 0) {
            const int a = fill(i);
            if (a > largest)
                second = largest, largest = a;
            else if (a > second)
                second = a;
        }
}

std::span<const IntPoint> ContourTracer::hull(std::span<const IntPoint> points) {
    hull_.clear();
    sorted_.assign(points.begin(), points.end());
    std::sort(sorted_.begin(), sorted_.end(),
              [](IntPoint a, IntPoint b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
    sorted_.erase(std::unique(sorted_.begin(), sorted_.end(),
                              [](IntPoint a, IntPoint b) { return a.x == b.x && a.y == b.y; }),
                  sorted_.end());
    const std::size_t n = sorted_.size();
    if (n < 3) {
        hull_.assign(sorted_.begin(), sorted_.end());
        return hull_;
    }
    // Andrew's monotone chain; a turn of zero is dropped (strictly convex).
    for (std::size_t i = 0; i < n; ++i) {
        while (hull_.size() >= 2 && cross(hull_[hull_.size() - 2], hull_.back(), sorted_[i]) >= 0)
            hull_.pop_back();
        hull_.push_back(sorted_[i]);
    }
    const std::size_t lower = hull_.size() + 1;
    for (std::size_t i = n - 1; i-- > 0;) {
        while (hull_.size() >= lower &&
               cross(hull_[hull_.size() - 2], hull_.back(), sorted_[i]) >= 0)
            hull_.pop_back();
        hull_.push_back(sorted_[i]);
    }
    hull_.pop_back();  // the first point again
    return hull_;
}

double polygon_area(std::span<const IntPoint> p) {
    if (p.empty()) return 0;
    double a = 0;
    IntPoint prev = p.back();
    for (const IntPoint& q : p) {
        a += static_cast<double>(prev.x) * q.y - static_cast<double>(prev.y) * q.x;
        prev = q;
    }
    return std::fabs(a * 0.5);
}

double polygon_perimeter(std::span<const IntPoint> p) {
    if (p.size() <= 1) return 0;
    double sum = 0;
    IntPoint prev = p.back();
    for (const IntPoint& q : p) {
        const float dx = static_cast<float>(q.x) - static_cast<float>(prev.x),
                    dy = static_cast<float>(q.y) - static_cast<float>(prev.y);
        sum += std::sqrt(dx * dx + dy * dy);
        prev = q;
    }
    return sum;
}

}  // namespace endotower::vision
