// FovMonitor: the per-frame field-of-view check. Measures the illuminated circle's
// edge along 64 rays from the calibrated centre, walking inwards from 1.3 radii (or
// the frame's edge) to 0.95 radii (0.7 where the disc is dark there), fits a circle to the edges
// found (rays with dark tissue at the rim are skipped, outliers trimmed) and compares it with the
// calibrated one: a shifted centre means the scope moved in its coupler, a different radius another
// scope (or zoom). Reads about 64 x 0.6 R pixels per frame, allocates nothing. A radius change
// beyond -30%..+30% reads kUnknown.
#pragma once

#include <array>

#include "endotower/calibration/field_of_view.hpp"
#include "endotower/hal/frame.hpp"

namespace endotower::calibration {

struct FovMonitorParams {
    double shift_tolerance_px = 3.0;  // centre moved further: kShifted
    double radius_tolerance = 0.03;   // radius changed by more (fraction): kScopeChanged
    int min_edge_contrast = 15;       // 8-bit levels between disc and surround on a ray
    int min_rays = 16;                // fewer usable rays: kUnknown (e.g. dark scene)
};

enum class FovStatus { kOk, kShifted, kScopeChanged, kUnknown };
const char* to_string(FovStatus s);

struct FovCheck {
    FovStatus status = FovStatus::kUnknown;
    FovCircle circle;  // measured (valid only when rays >= min_rays)
    int rays = 0;      // rays where the edge was found
    double shift_px = 0;
};

// Blackens every pixel of `frame` whose centre lies outside `circle` (a frame the
// caller owns, e.g. the analysis copy), so that nothing is detected there. Packed RGB
// and grey: 0; YUYV/UYVY: Y 16, U V 128, in whole pixel pairs (a pair half inside
// stays); NV12: the same per plane. Allocates nothing.
void mask_outside(const hal::Frame& frame, const FovCircle& circle);

class FovMonitor {
public:
    // `reference` from the calibration, in the pixels of the frames checked.
    explicit FovMonitor(const FovCircle& reference, FovMonitorParams params = {});
    // Checks one frame (any hal pixel format; reads luma only).
    FovCheck check(const hal::Frame& frame);

private:
    static constexpr int kRays = 64;
    FovCircle ref_;
    FovMonitorParams params_;
    std::array<double, kRays> cos_{}, sin_{}, xs_{}, ys_{}, res_{};
};

}  // namespace endotower::calibration
