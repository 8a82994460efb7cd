#include "endotower/vision/edge_pairing.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::vision {

namespace {

// Joins the extreme end points of a bin's segments along `dir` into one edge.
Segment merge(std::span<const Segment> segs, std::span<const int> members, Point2 dir) {
    Point2 lo{}, hi{};
    double tlo = 1e300, thi = -1e300;
    for (int i : members) {
        for (Point2 p : {segs[static_cast<std::size_t>(i)].a, segs[static_cast<std::size_t>(i)].b}) {
            const double t = p.x * dir.x + p.y * dir.y;
            if (t < tlo) tlo = t, lo = p;
            if (t > thi) thi = t, hi = p;
        }
    }
    return {lo, hi};
}

}  // namespace

EdgePair pair_edges(std::span<const Segment> segments, const EdgePairingParams& params) {
    EdgePair out;
    if (segments.empty()) return out;
    // At most a few hundred segments per frame; indices on the stack.
    constexpr std::size_t kMax = 512;
    int bin1[kMax], bin2[kMax];
    std::size_t n1 = 0, n2 = 0;
    const Segment& first = segments[0];
    int second = -1;
    for (std::size_t i = 0; i < segments.size() && i < kMax; ++i) {
        const Segment& s = segments[i];
        if (max_end_distance(s, first) <= params.bin_distance_px) {
            bin1[n1++] = static_cast<int>(i);
        } else if (second < 0) {
            if (angle_between_deg(s, first) > params.max_angle_deg) continue;
            second = static_cast<int>(i);
            bin2[n2++] = second;
        } else if (max_end_distance(s, segments[static_cast<std::size_t>(second)]) <= params.bin_distance_px) {
            bin2[n2++] = static_cast<int>(i);
        }
    }
    if (n2 == 0) return out;
    // Both edges are merged along bin 1's direction, so their ends correspond.
    double dx = first.b.x - first.a.x, dy = first.b.y - first.a.y;
    const double len = std::hypot(dx, dy);
    if (len == 0) return out;
    dx /= len, dy /= len;
    if (std::abs(dx) >= std::abs(dy) ? dx < 0 : dy < 0) dx = -dx, dy = -dy;  // left->right, top->bottom
    out.e1 = merge(segments, std::span<const int>(bin1, n1), {dx, dy});
    out.e2 = merge(segments, std::span<const int>(bin2, n2), {dx, dy});
    // Eq. 4.13 in the shared parameterisation: the average of the two lines.
    const bool x_major = std::abs(dx) >= std::abs(dy);
    const SlopeLine l1 = SlopeLine::through(out.e1, x_major), l2 = SlopeLine::through(out.e2, x_major);
    const SlopeLine mid{(l1.m + l2.m) / 2, (l1.b + l2.b) / 2, x_major};
    auto param = [&](Point2 p) { return x_major ? p.x : p.y; };
    const double t0 = std::min(std::min(param(out.e1.a), param(out.e1.b)), std::min(param(out.e2.a), param(out.e2.b)));
    const double t1 = std::max(std::max(param(out.e1.a), param(out.e1.b)), std::max(param(out.e2.a), param(out.e2.b)));
    out.midline = {mid.at(t0), mid.at(t1)};
    const Point2 centre{(out.midline.a.x + out.midline.b.x) / 2, (out.midline.a.y + out.midline.b.y) / 2};
    out.width_px = distance_to_line(centre, out.e1) + distance_to_line(centre, out.e2);
    out.found = true;
    return out;
}

}  // namespace endotower::vision
