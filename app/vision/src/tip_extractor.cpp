#include "endotower/vision/tip_extractor.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace endotower::vision {

namespace {

constexpr int kMaxSamples = 4096;

// HSV value (max of B, G, R) and saturation (255 (max - min) / max) of the pixels
// across the line at (x, y), averaged.
int sample_value(const hal::Frame& f, double x, double y, double nx, double ny, int halfwidth,
                 int* sat) {
    int sum = 0, ssum = 0, n = 0;
    for (int k = -halfwidth; k <= halfwidth; ++k) {
        const int px = static_cast<int>(std::lround(x + k * nx));
        const int py = static_cast<int>(std::lround(y + k * ny));
        if (px < 0 || py < 0 || px >= f.format.width || py >= f.format.height) continue;
        const std::uint8_t* p = f.data + static_cast<std::ptrdiff_t>(py) * f.format.stride + 3 * px;
        const int hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
        sum += hi;
        ssum += hi > 0 ? 255 * (hi - lo) / hi : 0;
        ++n;
    }
    *sat = n > 0 ? ssum / n : 0;
    return n > 0 ? sum / n : -1;
}

bool in_view(const hal::Frame& f, const FieldOfView& fov, double x, double y, double margin) {
    if (x < margin || y < margin || x > f.format.width - 1 - margin ||
        y > f.format.height - 1 - margin)
        return false;
    if (fov.radius <= 0) return true;
    return std::hypot(x - fov.cx, y - fov.cy) <= fov.radius - margin;
}

// Where the infinite lines through two segments meet; false if parallel.
bool intersect(const Segment& s, const Segment& t, Point2& out) {
    const double d1x = s.b.x - s.a.x, d1y = s.b.y - s.a.y, d2x = t.b.x - t.a.x, d2y = t.b.y - t.a.y;
    const double den = d1x * d2y - d1y * d2x;
    if (std::abs(den) < 1e-9) return false;
    const double u = ((t.a.x - s.a.x) * d2y - (t.a.y - s.a.y) * d2x) / den;
    out = {s.a.x + u * d1x, s.a.y + u * d1y};
    return true;
}

}  // namespace

TipResult extract_tip(const hal::Frame& f, const EdgePair& edges, Point2 toward_tip,
                      const FieldOfView& fov, const TipExtractorParams& params) {
    TipResult r;
    if (!edges.found || f.format.pixel_format != hal::PixelFormat::kBgr24) return r;
    const double tn = std::hypot(toward_tip.x, toward_tip.y);
    if (tn == 0) return r;
    Point2 dir{toward_tip.x / tn, toward_tip.y / tn};
    // Orient the midline along the tip direction.
    double mx = edges.midline.b.x - edges.midline.a.x, my = edges.midline.b.y - edges.midline.a.y;
    const double ml = std::hypot(mx, my);
    if (ml == 0) return r;
    mx /= ml, my /= ml;
    if (mx * dir.x + my * dir.y < 0) mx = -mx, my = -my;
    // Fig. 4.20: step one pixel in x, or in y for a steep tool.
    r.searched_in_y = std::abs(my) > std::abs(mx);
    const double step = 1.0 / (r.searched_in_y ? std::abs(my) : std::abs(mx));
    const double nx = -my, ny = mx;

    // The search starts at the end of the straight edges farthest along the midline.
    auto along = [&](Point2 p) {
        return (p.x - edges.midline.a.x) * mx + (p.y - edges.midline.a.y) * my;
    };
    double start =
        std::max({along(edges.e1.a), along(edges.e1.b), along(edges.e2.a), along(edges.e2.b)});
    // Filter 2: not beyond the edges' intersection when it lies ahead.
    double stop = params.search_length_px > 0 ? start + params.search_length_px : 1e9;
    Point2 cross;
    if (intersect(edges.e1, edges.e2, cross)) {
        const double c = along(cross);
        if (c > start) stop = std::min(stop, c);
    }
    // Back off a little so the head's own edge transition is inside the profile.
    start = std::max(0.0, start - 20.0);

    std::array<int, kMaxSamples> v{}, sat{};
    std::array<Point2, kMaxSamples> at{};
    int n = 0;
    for (double t = start; t <= stop && n < kMaxSamples; t += step) {
        const double x = edges.midline.a.x + t * mx, y = edges.midline.a.y + t * my;
        if (!in_view(f, fov, x, y, params.border_margin_px)) break;  // filter 3
        at[static_cast<std::size_t>(n)] = {x, y};
        v[static_cast<std::size_t>(n)] = sample_value(f, x, y, nx, ny, params.profile_halfwidth,
                                                      &sat[static_cast<std::size_t>(n)]);
        ++n;
    }
    // Changes between neighbours two samples apart (robust to one-pixel
    // anti-aliasing), over non-specular samples only (filter 1). The book takes the
    // largest; a tool's jaws often differ from its shaft more than from the tissue,
    // so with `last_strong_change` the farthest change of at least half the largest
    // is taken: the end of the tool, not the joint of shaft and jaws.
    int best = 0;
    for (int pass = 0; pass < (params.last_strong_change ? 2 : 1); ++pass) {
        const int floor = pass == 0 ? 0 : std::max(params.min_contrast, best / 2);
        for (int i = 0; i + 2 < n; ++i) {
            const int a = v[static_cast<std::size_t>(i)], b = v[static_cast<std::size_t>(i) + 2];
            if (a >= params.specular_value || b >= params.specular_value || a < 0 || b < 0)
                continue;
            // Grey metal against red tissue differs in saturation more than in value.
            const int c =
                std::max(std::abs(b - a), params.use_saturation
                                              ? std::abs(sat[static_cast<std::size_t>(i) + 2] -
                                                         sat[static_cast<std::size_t>(i)])
                                              : 0);
            if (pass == 0 ? c > best : c >= floor) {
                if (pass == 0) best = c;
                r.tip = at[static_cast<std::size_t>(i) + 1];
            }
        }
    }
    r.contrast = best;
    r.found = best >= params.min_contrast;
    return r;
}

}  // namespace endotower::vision
