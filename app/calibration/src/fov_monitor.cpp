#include "endotower/calibration/fov_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace endotower::calibration {

namespace {

// Luma of pixel (x, y), or -1 outside the frame. For colour formats an integer
// approximation of Rec. 601 is plenty for an edge that is dark on one side.
int luma(const hal::Frame& f, int x, int y) {
    if (x < 0 || y < 0 || x >= f.format.width || y >= f.format.height) return -1;
    const std::uint8_t* row = f.data + static_cast<std::size_t>(y) * f.format.stride;
    switch (f.format.pixel_format) {
        case hal::PixelFormat::kBgr24: {
            const std::uint8_t* p = row + 3 * x;
            return (p[0] + 2 * p[1] + p[2]) >> 2;
        }
        case hal::PixelFormat::kRgb24: {
            const std::uint8_t* p = row + 3 * x;
            return (p[0] + 2 * p[1] + p[2]) >> 2;
        }
        case hal::PixelFormat::kBgra32: {
            const std::uint8_t* p = row + 4 * x;
            return (p[0] + 2 * p[1] + p[2]) >> 2;
        }
        case hal::PixelFormat::kGray8:
        case hal::PixelFormat::kNv12:
            return row[x];
        case hal::PixelFormat::kYuyv:
            return row[2 * x];
        case hal::PixelFormat::kUyvy:
            return row[2 * x + 1];
    }
    return -1;
}

}  // namespace

const char* to_string(FovStatus s) {
    switch (s) {
        case FovStatus::kOk:
            return "ok";
        case FovStatus::kShifted:
            return "shifted";
        case FovStatus::kScopeChanged:
            return "scope_changed";
        case FovStatus::kUnknown:
            return "unknown";
    }
    return "unknown";
}

FovMonitor::FovMonitor(const FovCircle& reference, FovMonitorParams params)
    : ref_(reference), params_(params) {
    for (int i = 0; i < kRays; ++i) {
        const double a = 2.0 * M_PI * i / kRays;
        cos_[i] = std::cos(a);
        sin_[i] = std::sin(a);
    }
}

FovCheck FovMonitor::check(const hal::Frame& frame) {
    FovCheck out;
    if (!ref_.valid() || frame.data == nullptr) return out;
    const int r_near = static_cast<int>(0.95 * ref_.radius),
              r_in = static_cast<int>(0.7 * ref_.radius),
              r_max = static_cast<int>(1.3 * ref_.radius);
    const int w = frame.format.width, h = frame.format.height;
    int n = 0;
    for (int i = 0; i < kRays; ++i) {
        auto at = [&](int r) {
            return luma(frame, static_cast<int>(std::lround(ref_.cx + r * cos_[i])),
                        static_cast<int>(std::lround(ref_.cy + r * sin_[i])));
        };
        // The ray ends at 1.3 R or the frame's edge (16:9 frames clip the circle's
        // top and bottom); it must pass the rim by a few pixels to measure it.
        int r1 = r_max;
        while (r1 > r_in && (std::lround(ref_.cx + r1 * cos_[i]) < 0 ||
                             std::lround(ref_.cx + r1 * cos_[i]) >= w ||
                             std::lround(ref_.cy + r1 * sin_[i]) < 0 ||
                             std::lround(ref_.cy + r1 * sin_[i]) >= h))
            --r1;
        if (r1 < ref_.radius + 3) continue;
        // The disc's level just inside the calibrated rim; deeper in (0.7 R) when that is
        // dark: a smaller circle (another scope), or dark tissue at the rim.
        // The surround must be dark against the disc (under a third of its level), so
        // vignetting inside the disc is never taken for the rim.
        const int outside = at(r1);
        auto usable = [&](int in) {
            return in - outside >= params_.min_edge_contrast && 3 * outside < in;
        };
        int inside = at(r_near), r_stop = r_near;
        if (!usable(inside)) inside = at(r_in), r_stop = r_in;
        if (!usable(inside)) continue;
        // Inwards from the dark surround to the first lit sample: the rim, not an
        // edge in the scene inside it.
        const double mid = 0.5 * (inside + outside);
        int prev = outside;
        for (int r = r1 - 1; r >= r_stop; --r) {
            const int v = at(r);
            if (v >= mid) {
                const double rr = r + (v - mid) / static_cast<double>(v - prev);
                xs_[n] = ref_.cx + rr * cos_[i];
                ys_[n] = ref_.cy + rr * sin_[i];
                ++n;
                break;
            }
            prev = v;
        }
    }
    // Outliers (an edge in the scene, not the rim): refit without the rays off the
    // circle by more than max(3 px, 3x the median residual), three times.
    for (int pass = 0; pass < 3 && n >= params_.min_rays; ++pass) {
        if (fit_circle(xs_.data(), ys_.data(), n, out.circle) < 0) break;
        for (int i = 0; i < n; ++i)
            res_[i] = std::abs(std::hypot(xs_[i] - out.circle.cx, ys_[i] - out.circle.cy) -
                               out.circle.radius);
        std::array<double, kRays> sorted = res_;
        std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.begin() + n);
        const double limit = std::max(3.0, 3.0 * sorted[n / 2]);
        int m = 0;
        for (int i = 0; i < n; ++i)
            if (res_[i] <= limit) xs_[m] = xs_[i], ys_[m] = ys_[i], ++m;
        if (m == n) break;
        n = m;
    }
    out.rays = n;
    if (n < params_.min_rays || fit_circle(xs_.data(), ys_.data(), n, out.circle) < 0) {
        out.circle = {};
        return out;
    }
    out.shift_px = std::hypot(out.circle.cx - ref_.cx, out.circle.cy - ref_.cy);
    if (std::abs(out.circle.radius - ref_.radius) > params_.radius_tolerance * ref_.radius)
        out.status = FovStatus::kScopeChanged;
    else if (out.shift_px > params_.shift_tolerance_px)
        out.status = FovStatus::kShifted;
    else
        out.status = FovStatus::kOk;
    return out;
}

namespace {

// Fills pixels [x0, x1) of one row with black in the frame's format.
void fill_black(std::uint8_t* row, hal::PixelFormat f, int x0, int x1) {
    if (x1 <= x0) return;
    switch (f) {
        case hal::PixelFormat::kYuyv:
        case hal::PixelFormat::kUyvy: {
            const bool yuyv = f == hal::PixelFormat::kYuyv;
            x0 += x0 & 1;  // whole pairs only
            x1 -= x1 & 1;
            for (int x = x0; x < x1; ++x) {
                row[2 * x + (yuyv ? 0 : 1)] = 16;
                row[2 * x + (yuyv ? 1 : 0)] = 128;
            }
            return;
        }
        case hal::PixelFormat::kNv12:
            std::memset(row + x0, 16, static_cast<std::size_t>(x1 - x0));
            return;
        default: {
            const int bpp = hal::bytes_per_pixel(f);
            std::memset(row + static_cast<std::ptrdiff_t>(bpp) * x0, 0,
                        static_cast<std::size_t>(bpp) * (x1 - x0));
        }
    }
}

// The pixels of row y (centres at y + 0.5) inside the circle: [x0, x1).
void inside_span(const FovCircle& c, double y, int width, int& x0, int& x1) {
    const double dy = y - c.cy;
    if (std::abs(dy) >= c.radius) {
        x0 = x1 = width;
        return;
    }
    const double half = std::sqrt(c.radius * c.radius - dy * dy);
    x0 = std::clamp(static_cast<int>(std::ceil(c.cx - half - 0.5)), 0, width);
    x1 = std::clamp(static_cast<int>(std::floor(c.cx + half - 0.5)) + 1, x0, width);
}

}  // namespace

void mask_outside(const hal::Frame& frame, const FovCircle& circle) {
    const hal::FrameFormat& f = frame.format;
    if (frame.data == nullptr || !circle.valid()) return;
    for (int y = 0; y < f.height; ++y) {
        int x0 = 0, x1 = 0;
        inside_span(circle, y + 0.5, f.width, x0, x1);
        std::uint8_t* row = frame.data + static_cast<std::ptrdiff_t>(y) * f.stride;
        fill_black(row, f.pixel_format, 0, x0);
        fill_black(row, f.pixel_format, x1, f.width);
    }
    if (f.pixel_format != hal::PixelFormat::kNv12) return;
    // The interleaved chroma plane: one row per two luma rows, one pair per two pixels.
    std::uint8_t* uv = frame.data + static_cast<std::ptrdiff_t>(f.height) * f.stride;
    for (int y = 0; y < f.height / 2; ++y) {
        int x0 = 0, x1 = 0;
        inside_span(circle, 2 * y + 1.0, f.width, x0, x1);
        std::uint8_t* row = uv + static_cast<std::ptrdiff_t>(y) * f.stride;
        const int p0 = (x0 + 1) / 2, p1 = x1 / 2;
        std::memset(row, 128, 2 * static_cast<std::size_t>(p0));
        if (p1 < f.width / 2)
            std::memset(row + 2 * p1, 128, 2 * static_cast<std::size_t>(f.width / 2 - p1));
    }
}

}  // namespace endotower::calibration
