#include "endotower/calibration/fov_monitor.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace endotower::calibration
