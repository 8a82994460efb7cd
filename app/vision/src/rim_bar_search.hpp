// RimBarSearch: straight bars of tool likelihood that come in from the rim of the
// picture, for LikelihoodToolTracker (docs/tracking.md, "Bars from the rim").
//
// Why: a dark shaft in shadow can have the colour of the tissue beside it (sznitman_lap:
// BGR 62, 55, 68 against 58, 53, 70), so its pixels sit below even odds and its region
// breaks up or merges with a grey band along the rim. Its likelihood is still higher
// than that of the tissue on both sides, all along a straight line from the rim.
//
// Input: the smoothed tool probability and the eroded lit field of view at the analysis
// size (W x H), reduced here to half size (2 x 2 mean; a block is lit when all four are,
// the picture's border counts as unlit). Per orientation (kOrientations, 5 degrees
// apart, each scanned both ways: inwards along theta and theta + 180), every line across
// the picture at that orientation, one half-size pixel apart: per point the bar's mean S
// over `widths` px across the line and its flanks' means L and R (the same width, one px
// apart from it); the point is good where the whole footprint is lit, S >= `min_level`
// and S - max(L, R) >= `min_contrast`. A bar: from the first lit point r0, a good point
// within `touch_fraction` x W of it (over a band along the rim), then the run of points
// until more than one width of points is not good; kept when it reaches at least
// `min_length_fraction` x W from r0 to its last good point (the tip) and `min_fill` of
// its points are good. Bars within 20 degrees and two widths (+ 4 px) of a stronger one
// are the same bar; kMaxBars are kept.
// Cost: `orientations_per_frame` (6) orientations are scanned a frame, in turn (all 36
// in 6 frames, 0.24 s at 25 Hz; 3 a frame found sznitman_lap's dark tool 8 frames
// later); the kept bars of the others are measured again in this frame along their
// line and its neighbours (one column aside, one orientation round their rim point): a
// tool moves and turns a little between scans. RimBar::frames counts the
// frames in a row a bar has been found. Output in analysis pixels. No allocation after
// configure(); no exceptions. Parameters: the prototype's (docs/tracking.md), fixed
// before it was scored.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "endotower/vision/tool_pose.hpp"

namespace endotower::vision::detail {

// Distance of (x, y) to the segment a-b (the likelihood tracker's too).
inline double segment_distance(Point2 a, Point2 b, double x, double y) {
    const double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy;
    const double t = l2 > 0 ? std::clamp(((x - a.x) * dx + (y - a.y) * dy) / l2, 0.0, 1.0) : 0.0;
    return std::hypot(x - a.x - t * dx, y - a.y - t * dy);
}

struct RimBarParams {
    std::array<int, 2> widths{4, 6};        // half-size px (8, 12 at 320 px)
    int min_level = 80, min_contrast = 24;  // of 255
    double touch_fraction = 0.06, min_length_fraction = 0.15, min_fill = 0.7;
    int orientations_per_frame = 6;
};

struct RimBar {
    Point2 rim, tip;                                     // analysis px
    double width = 0, length = 0, score = 0, level = 0;  // width, length in analysis px
    double inward_deg = 0;                               // from the rim towards the tip
    int frames = 0;                                      // frames in a row it has been found
};

class RimBarSearch {
public:
    static constexpr int kOrientations = 36, kKeptPerScan = 2, kMaxBars = 6;
    explicit RimBarSearch(RimBarParams params = {}) : params_(params) {}
    void configure(int width, int height);
    // Scans this frame's orientations and measures the kept bars again; the bars after
    // suppression, strongest first (valid until the next call).
    std::span<const RimBar> search(const std::uint8_t* prob, const std::uint8_t* lit,
                                   std::size_t stride);

private:
    struct Kept {
        int orientation = -1, column = 0, width_index = 0;
        bool reverse = false;
        RimBar bar;
    };
    struct Line;
    Line line(int orientation, int column) const;
    bool measure(const Line& l, int width_index, bool reverse, RimBar& out) const;
    void scan(int orientation);

    RimBarParams params_;
    int w_ = 0, h_ = 0, d_ = 0, next_ = 0;
    std::vector<std::uint8_t> prob_, lit_;  // half size
    std::vector<std::uint8_t> flags_;       // per (row, column) of one scan: valid, good bits
    std::vector<std::uint8_t> contrast_;    // per width, row, column: S - max(L, R), clamped
    std::vector<std::int32_t> sum_p_, sum_l_;
    std::vector<int> col_first_, col_last_;  // per width, column: first, last lit row
    std::vector<Kept> kept_, scanned_;
    std::vector<RimBar> out_;
};

}  // namespace endotower::vision::detail
