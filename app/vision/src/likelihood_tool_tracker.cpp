// LikelihoodToolTracker (likelihood_tool_tracker.hpp).
#include "endotower/vision/likelihood_tool_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <span>
#include <vector>

#include "constant_velocity.hpp"
#include "endotower/vision/area_mean.hpp"
#include "endotower/vision/mask_ops.hpp"
#include "reduce_frame.hpp"
#include "rim_bar_search.hpp"

namespace endotower::vision {

namespace {

struct Candidate {
    double area = 0, length = 0, width = 0, shaft_width = 0, confidence = 0;
    double axis_deg = 0;  // from the tip towards the rim
    Point2 tip, rim_end;
    bool has_edges = false;
    bool split = false;       // cut from a region shared with another tool
    bool end_hidden = false;  // its far end runs under the other tool
    bool solid = true;        // min_solid_fraction of it tool-coloured before the blur
    double support = 0;       // its length, or a bar's along it (analysis px); ranks tools
    int track = -1;           // the track whose prediction cut it out, or -1
    Segment e1, e2;
};

// One tool over time (analysis px; angles in degrees from the tip towards the rim,
// unwrapped): constant-velocity filters on the tip and the axis angle.
struct Track {
    int id = -1, missed = 0, coasted = 0;
    double width = 0, confidence = 0;
    Point2 rim_end;
    ConstantVelocity x, y, angle;
    Point2 tip() const { return {x.position(), y.position()}; }
};

// Process and measurement noise of the track filters (analysis px, degrees, per
// frame). They matter only where two tools share a region (a single tool's own
// measurement is always taken): a hand changes a tool's speed by a few px per frame
// (the simulator's crossing moves 2 analysis px per frame at 3 cm/s); the measurement
// noise is the tip's spread on a still tool.
constexpr double kTipAccel = 2.0, kTipNoise = 1.5, kAngleAccel = 1.0, kAngleNoise = 2.0;
// A split region's measurement further than this from the prediction (in standard
// deviations of the innovation, at least one tool width) or turned by more than
// kAngleGateDeg is another tool's part; the track coasts on its prediction instead.
constexpr double kGateSigmas = 4.0, kAngleGateDeg = 20.0;
// A region short of solid (glints joined to a tool in bright light) is taken only as a
// live track's continuation: summed cost (tip distance in widths + turn in
// kAngleGateDeg) at most this.
constexpr double kContinuationCost = 2.0;
// Per frame, the share of a track's speed kept while its end is hidden under the other
// tool (measured then only up to the prediction): a crossing's tip reappears within a
// few frames, a tip at rest must not creep on.
constexpr double kHiddenVelocityDamping = 0.8;
// Across a band: the share of tool-coloured points between the band and the rim (as a
// bar from the rim needs, RimBarParams::min_fill), and how far the region beyond the band
// may turn from the line (its axis is skewed by whatever joins it along the rim).
constexpr double kBridgeFill = 0.7, kBridgeTurnDeg = 30.0;
// The axis near the tip: fitted to the region's pixels within this share of its length
// from the tip (the half of it nearer the tip).
constexpr double kTipAxisReach = 0.5;

double angle_diff_deg(double a, double b) {
    return std::abs(std::remainder(a - b, 360.0));
}

using detail::segment_distance;

struct Px {
    std::int16_t x, y;
};

struct RimPixel {
    double angle, x, y;
};

// An elongated, solid region that does not reach the rim: a tool's jaws and the end of
// its shaft cut off from the rest by a band across it (a marker ring, a crossing
// instrument), or tissue. Analysis px.
struct Floating {
    std::array<Point2, 2> ends;
    double ux = 1, uy = 0;  // the principal axis, from ends[0] towards ends[1]
    double area = 0, length = 0, width = 0, confidence = 0;
};

struct Line {
    double px = 0, py = 0, ux = 1, uy = 0;  // a point and the unit direction
    double distance(double x, double y) const { return std::abs((x - px) * uy - (y - py) * ux); }
};

// Principal axis of weighted points; false when there are fewer than 3.
template <typename Pred>
bool fit_axis(const Px* begin, const Px* end, Pred use, Line& out, double& n, double& l1,
              double& l2) {
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    n = 0;
    for (const Px* p = begin; p != end; ++p) {
        if (!use(p)) continue;
        n += 1, sx += p->x, sy += p->y, sxx += double(p->x) * p->x, syy += double(p->y) * p->y,
            sxy += double(p->x) * p->y;
    }
    if (n < 3) return false;
    const double mx = sx / n, my = sy / n;
    const double cxx = sxx / n - mx * mx, cyy = syy / n - my * my, cxy = sxy / n - mx * my;
    const double tr = cxx + cyy, det = cxx * cyy - cxy * cxy;
    l1 = tr / 2 + std::sqrt(std::max(0.0, tr * tr / 4 - det));
    l2 = std::max(1e-9, tr - l1);
    const double a = 0.5 * std::atan2(2 * cxy, cxx - cyy);
    out = {mx, my, std::cos(a), std::sin(a)};
    return true;
}

// A region part's pixels (those `use` picks) along `axis`: the least and greatest
// projection, the greatest of those `seen` keeps, the tool probability's sum and the
// count of solid pixels (`raw` at least `threshold`).
struct AxisSpan {
    double lo = std::numeric_limits<double>::max(), hi = -lo, hi_seen = -lo, psum = 0, solid = 0;
};
template <typename Use, typename Seen>
AxisSpan span_along(const Px* begin, const Px* end, const Line& axis, Use use, Seen seen,
                    const cv::Mat& prob, const cv::Mat& raw, int threshold) {
    AxisSpan s;
    for (const Px* p = begin; p != end; ++p)
        if (use(p)) {
            const double t = (p->x - axis.px) * axis.ux + (p->y - axis.py) * axis.uy;
            s.lo = std::min(s.lo, t), s.hi = std::max(s.hi, t);
            if (seen(p)) s.hi_seen = std::max(s.hi_seen, t);
            s.psum += prob.at<std::uint8_t>(p->y, p->x);
            s.solid += raw.at<std::uint8_t>(p->y, p->x) >= threshold;
        }
    return s;
}

// The two ends of a part between `lo` and `hi` along `axis`: the mean of its pixels
// within `band` of each (of those `seen` keeps at the high end), and how many of its
// pixels lie before `mid`.
struct AxisEnds {
    Point2 lo, hi;
    double before_mid = 0;
};
template <typename Use, typename Seen>
AxisEnds ends_along(const Px* begin, const Px* end, const Line& axis, Use use, Seen seen, double lo,
                    double hi, double band, double mid) {
    AxisEnds e;
    double n_lo = 0, n_hi = 0;
    for (const Px* p = begin; p != end; ++p)
        if (use(p)) {
            const double t = (p->x - axis.px) * axis.ux + (p->y - axis.py) * axis.uy;
            if (t <= lo + band) e.lo.x += p->x, e.lo.y += p->y, n_lo += 1;
            if (t >= hi - band && t <= hi && seen(p)) e.hi.x += p->x, e.hi.y += p->y, n_hi += 1;
            e.before_mid += t < mid;
        }
    e.lo = {e.lo.x / n_lo, e.lo.y / n_lo};
    e.hi = {e.hi.x / n_hi, e.hi.y / n_hi};
    return e;
}

// The axis near a region's tip (docs/tracking.md, "The axis near the tip"): the
// principal axis of its pixels within kTipAxisReach of its length from the tip, where the
// ray from the tip along it runs through more of the region (within half a width) than
// the ray towards the rim end. Something joined to the shaft at the rim (a band along
// the edge of the picture) skews the whole region's axis; something joined near the tip
// (the other tool of a crossing), the near part's.
double tip_axis(const Px* begin, const Px* end, const Candidate& c) {
    double n = 0, l1 = 0, l2 = 0;
    Line near;
    const double reach = kTipAxisReach * c.length;
    auto within = [&](const Px* p) { return std::hypot(p->x - c.tip.x, p->y - c.tip.y) <= reach; };
    if (!fit_axis(begin, end, within, near, n, l1, l2)) return c.axis_deg;
    double ux = near.ux, uy = near.uy;
    if ((near.px - c.tip.x) * ux + (near.py - c.tip.y) * uy < 0) ux = -ux, uy = -uy;
    const double a = c.axis_deg * M_PI / 180.0, vx = std::cos(a), vy = std::sin(a);
    const double half = std::max(1.5, 0.5 * c.width);
    int along_near = 0, along_whole = 0;
    for (const Px* p = begin; p != end; ++p) {
        const double dx = p->x - c.tip.x, dy = p->y - c.tip.y;
        along_near += dx * ux + dy * uy >= 0 && std::abs(dx * uy - dy * ux) <= half;
        along_whole += dx * vx + dy * vy >= 0 && std::abs(dx * vy - dy * vx) <= half;
    }
    return along_near > along_whole ? std::atan2(uy, ux) * 180.0 / M_PI : c.axis_deg;
}

// Grey (mean of B, G, R) at a sub-pixel position of a BGR image, bilinear.
double grey_at(const cv::Mat& img, double x, double y) {
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    if (x0 < 0 || y0 < 0 || x0 + 1 >= img.cols || y0 + 1 >= img.rows) return -1;
    const double fx = x - x0, fy = y - y0;
    auto g = [&](int xx, int yy) {
        const std::uint8_t* p = img.ptr<std::uint8_t>(yy) + 3 * xx;
        return (p[0] + p[1] + p[2]) / 3.0;
    };
    return (1 - fy) * ((1 - fx) * g(x0, y0) + fx * g(x0 + 1, y0)) +
           fy * ((1 - fx) * g(x0, y0 + 1) + fx * g(x0 + 1, y0 + 1));
}

// Moves a coarse silhouette edge (full-resolution px) onto the image's strongest
// step within `reach` px along its normal, at 16 points between `begin` and `end`
// (0..1, from a): a line through the sub-pixel steps (parabola fit of the gradient
// peak), or the coarse edge where too few steps are found.
Segment refine_edge(const cv::Mat& img, const Segment& e, double begin, double end, double reach) {
    constexpr int kSamples = 16;
    const double dx = e.b.x - e.a.x, dy = e.b.y - e.a.y, len = std::hypot(dx, dy);
    if (len < 4) return e;
    const double ux = dx / len, uy = dy / len, nx = -uy, ny = ux;
    std::array<double, kSamples> ts{}, os{};
    int n = 0;
    // grad below holds 2 steps + 1 values (reach is 2.5 analysis px at full size: 15
    // steps at 1920 px; an 8K frame would ask for 60).
    const int steps = std::min(static_cast<int>(std::ceil(reach)), 31);
    for (int k = 0; k < kSamples; ++k) {
        const double t = (begin + (end - begin) * (k + 0.5) / kSamples) * len;
        const double px = e.a.x + t * ux, py = e.a.y + t * uy;
        double best = 0;
        int at = 0;
        std::array<double, 64> grad{};
        for (int j = -steps; j <= steps; ++j) {
            const double g0 = grey_at(img, px + (j - 0.5) * nx, py + (j - 0.5) * ny),
                         g1 = grey_at(img, px + (j + 0.5) * nx, py + (j + 0.5) * ny);
            if (g0 < 0 || g1 < 0) continue;
            grad[j + steps] = std::abs(g1 - g0);
            if (grad[j + steps] > best) best = grad[j + steps], at = j;
        }
        if (best < 8 || at == -steps || at == steps) continue;  // no clear step in reach
        const double gm = grad[at - 1 + steps], g0 = grad[at + steps], gp = grad[at + 1 + steps];
        const double den = gm - 2 * g0 + gp;
        const double off = at + (std::abs(den) > 1e-9 ? 0.5 * (gm - gp) / den : 0.0);
        ts[n] = t, os[n] = off, ++n;
    }
    if (n < 6) return e;
    double st = 0, so = 0, stt = 0, sto = 0;
    for (int k = 0; k < n; ++k)
        st += ts[k], so += os[k], stt += ts[k] * ts[k], sto += ts[k] * os[k];
    const double den = n * stt - st * st;
    const double slope = std::abs(den) > 1e-9 ? (n * sto - st * so) / den : 0,
                 icpt = (so - slope * st) / n;
    auto at_t = [&](double t) {
        const double o = icpt + slope * t;
        return Point2{e.a.x + t * ux + o * nx, e.a.y + t * uy + o * ny};
    };
    return {at_t(0), at_t(len)};
}

}  // namespace

struct LikelihoodToolTracker::Work {
    double scale = 1.0;
    cv::Mat small, prob, raw, gray, lit, eroded, binary, labels;
    std::vector<std::uint16_t> cells;  // one row's ToolLikelihood cells
    AreaMean reduce;                 // INTER_AREA, no allocation (factor <= 15: else cv::resize)
    MaskOps ops;                     // the image operations, OpenCV's bytes, no allocation
    std::vector<std::uint32_t> rim;  // distance to the unlit surround, 16.16 fixed point
    std::array<int, 15> fov_rows{};  // the erosion's ellipse, half-width per row
    int fov_row_count = 0;
    std::vector<int> offsets, fill;
    std::vector<Px> pixels;
    std::vector<RimPixel> entries;
    std::vector<std::pair<std::size_t, std::size_t>> runs;  // [first, last) into entries
    std::vector<std::uint8_t> owner;                        // per region pixel: which line
    std::vector<Candidate> candidates;
    std::vector<Floating> floating;
    std::array<Track, ToolTracker::kMaxTools> tracks{};
    double fov_cx = 0, fov_cy = 0, fov_r = 0;
    detail::RimBarSearch bars;
};

LikelihoodToolTracker::LikelihoodToolTracker(const ToolLikelihood& model,
                                             LikelihoodToolTrackerParams params)
    : model_(model), params_(params), work_(std::make_unique<Work>()) {}
LikelihoodToolTracker::~LikelihoodToolTracker() = default;

void LikelihoodToolTracker::configure(const hal::FrameFormat& format) {
    Work& w = *work_;
    w.scale = std::min(1.0, static_cast<double>(params_.analysis_width) / format.width);
    const int sw = std::max(1, static_cast<int>(std::lround(format.width * w.scale)));
    const int sh = std::max(1, static_cast<int>(std::lround(format.height * w.scale)));
    w.small.create(sh, sw, CV_8UC3);
    w.prob.create(sh, sw, CV_8U);
    w.cells.resize(static_cast<std::size_t>(sw));
    w.raw.create(sh, sw, CV_8U);
    w.lit.create(sh, sw, CV_8U);
    w.eroded.create(sh, sw, CV_8U);
    w.gray.create(sh, sw, CV_8U);
    w.binary.create(sh, sw, CV_8U);
    w.labels.create(sh, sw, CV_32S);
    w.reduce.configure(format.width, format.height, sw, sh, 3);
    w.ops.configure(sw, sh);
    w.rim.assign(static_cast<std::size_t>(sw) * sh, 0);
    w.fov_row_count = MaskOps::ellipse_rows(params_.surround_margin_px, w.fov_rows);
    // Every list at its largest possible size, so no frame reallocates: regions at most
    // one per 2 x 2 block (no two 8-adjacent), rim pixels and their runs at most all
    // pixels.
    const auto area = static_cast<std::size_t>(sw) * sh;
    const std::size_t regions =
        static_cast<std::size_t>((sw + 1) / 2) * static_cast<std::size_t>((sh + 1) / 2) + 2;
    w.offsets.reserve(regions);
    w.fill.reserve(regions);
    w.pixels.reserve(area);
    w.entries.reserve(area);
    w.runs.reserve(area);
    w.owner.reserve(area);
    // Candidates: regions of at least min_area_fraction of the picture, each cut in
    // at most kMaxTools.
    const double f = params_.min_area_fraction;
    const std::size_t large = f > 0 ? static_cast<std::size_t>(1.0 / f) + 1 : regions;
    // ... and the floating regions that continue one across a band, and the bars.
    w.floating.reserve(std::min(large, regions));
    w.candidates.reserve(kMaxTools * std::min(large, regions) + w.floating.capacity() + 6);
    w.bars.configure(sw, sh);
    for (Track& t : w.tracks) t = Track{};
}

std::size_t LikelihoodToolTracker::track(const hal::Frame& frame,
                                         std::span<ToolEstimate, kMaxTools> out) {
    Work& w = *work_;
    if (frame.format.pixel_format != hal::PixelFormat::kBgr24 || w.small.empty() ||
        !model_.trained())
        return 0;
    const cv::Mat full(frame.format.height, frame.format.width, CV_8UC3, frame.data,
                       frame.format.stride);
    detail::reduce_frame(frame, w.reduce, w.small);
    const int W = w.small.cols, H = w.small.rows;

    // Probability per pixel; brightness histogram for the field of view.
    // The cells a row at a time, vectorised (ToolLikelihood::cells); the lookups one by one.
    std::array<int, 256> hist{};
    const std::uint8_t* table = model_.table().data();
    for (int y = 0; y < H; ++y) {
        const std::uint8_t* p = w.small.ptr<std::uint8_t>(y);
        std::uint8_t* q = w.prob.ptr<std::uint8_t>(y);
        std::uint8_t* g = w.gray.ptr<std::uint8_t>(y);
        ToolLikelihood::cells(p, w.cells.data(), W);
        for (int x = 0; x < W; ++x, p += 3) {
            q[x] = table[w.cells[static_cast<std::size_t>(x)]];
            g[x] = static_cast<std::uint8_t>((p[0] + p[1] + p[2]) / 3);
            ++hist[g[x]];
        }
    }
    // The lit field of view: brighter than `surround_fraction` of the median of the
    // picture (at least `surround_level`), so a dim letterbox border (real video) is as
    // dark as the black surround of a scope; blurred first, so a dark shaft inside the
    // lit area stays inside it.
    int median = 0;
    for (int acc = 0; median < 255 && (acc += hist[median]) < W * H / 2;) ++median;
    const double level =
        std::max<double>(params_.surround_level, params_.surround_fraction * median);
    // The operations are OpenCV's, byte for byte (MaskOps, AreaMean: tested against
    // cv::blur + threshold + moments, distanceTransform, erode, GaussianBlur + threshold +
    // and, morphologyEx OPEN, connectedComponents), without their per-call allocations.
    auto plane = [](cv::Mat& m) {
        return BytePlane{m.data, m.cols, m.rows, static_cast<std::size_t>(m.step)};
    };
    // cv::threshold compares 8-bit pixels with the threshold's floor.
    const LitMoments fov =
        w.ops.lit_field(plane(w.gray), static_cast<int>(std::floor(level)), plane(w.lit));
    if (fov.m00 <= 0) return 0;
    w.fov_cx = fov.m10 / fov.m00;
    w.fov_cy = fov.m01 / fov.m00;
    w.fov_r = std::sqrt(fov.m00 / M_PI);
    // Distance to the edge of the picture (unlit, or the frame's border).
    w.ops.chamfer(plane(w.lit), 0, 0, W, H, w.rim.data());
    w.ops.morph(plane(w.lit), plane(w.eroded),
                std::span<const int>(w.fov_rows.data(), static_cast<std::size_t>(w.fov_row_count)),
                true);
    w.prob.copyTo(w.raw);  // before smoothing: how solidly a region is tool-coloured
    w.ops.smooth_at_least(plane(w.raw), params_.threshold, plane(w.eroded), plane(w.binary),
                          plane(w.prob));
    w.ops.open3(plane(w.binary), plane(w.binary));
    const int n = w.ops.label(plane(w.binary), w.labels.ptr<std::int32_t>(0));

    // Pixels grouped by region (counting sort), so each region is visited once.
    w.offsets.assign(static_cast<std::size_t>(n) + 1, 0);
    for (int y = 0; y < H; ++y) {
        const int* l = w.labels.ptr<int>(y);
        for (int x = 0; x < W; ++x) ++w.offsets[l[x] + 1];
    }
    for (int i = 1; i <= n; ++i) w.offsets[i] += w.offsets[i - 1];
    w.fill.assign(w.offsets.begin(), w.offsets.end() - 1);
    w.pixels.resize(static_cast<std::size_t>(W) * H);
    for (int y = 0; y < H; ++y) {
        const int* l = w.labels.ptr<int>(y);
        for (int x = 0; x < W; ++x)
            if (l[x] != 0)
                w.pixels[w.fill[l[x]]++] = {static_cast<std::int16_t>(x),
                                            static_cast<std::int16_t>(y)};
    }
    // Distance of a point to the edge of the picture: the lit circle or the frame.
    auto rim_distance = [&](double x, double y) {
        const int xi = std::clamp(static_cast<int>(std::lround(x)), 0, W - 1),
                  yi = std::clamp(static_cast<int>(std::lround(y)), 0, H - 1);
        // cv::distanceTransform's float: the 16.16 value converted, then scaled.
        const float rim =
            static_cast<float>(w.rim[static_cast<std::size_t>(yi) * W + xi]) * (1.f / 65536.f);
        return std::min<double>({rim, x + 1, y + 1, W - x, H - y});
    };
    w.candidates.clear();
    w.floating.clear();
    const std::size_t nt = std::min(params_.max_tools, kMaxTools);
    for (std::size_t t = 0; t < nt; ++t)
        if (w.tracks[t].id >= 0) {
            w.tracks[t].x.predict(kTipAccel);
            w.tracks[t].y.predict(kTipAccel);
            w.tracks[t].angle.predict(kAngleAccel);
        }
    std::array<Point2, kMaxTools> predicted{};
    for (std::size_t t = 0; t < nt; ++t) predicted[t] = w.tracks[t].tip();
    const bool two_tracks = nt == 2 && w.tracks[0].id >= 0 && w.tracks[1].id >= 0;
    const double min_area = params_.min_area_fraction * W * H,
                 touch = params_.border_touch_fraction * W;
    // A region off the rim that is elongated and solid like a tool: its two ends (the
    // mean of its pixels within 3 % of the length of each extreme) along its axis.
    auto measure_floating = [&](const Px* begin, const Px* end, Floating& f) {
        double n = 0, l1 = 0, l2 = 0;
        Line axis;
        const auto all = [](const Px*) { return true; };
        if (!fit_axis(begin, end, all, axis, n, l1, l2) || l2 <= 0 ||
            std::sqrt(l1 / l2) < params_.min_elongation)
            return false;
        const AxisSpan span =
            span_along(begin, end, axis, all, all, w.prob, w.raw, params_.threshold);
        if (span.solid < params_.min_solid_fraction * n) return false;
        const double lo = span.lo, hi = span.hi, band = std::max(1.0, 0.03 * (hi - lo));
        const AxisEnds ends = ends_along(begin, end, axis, all, all, lo, hi, band, 0.5 * (lo + hi));
        f.ends = {ends.lo, ends.hi};
        f.ux = axis.ux, f.uy = axis.uy;
        f.area = n;
        f.length = std::max(1.0, hi - lo);
        f.width = n / f.length;
        f.confidence = std::clamp(span.psum / n / 255.0, 0.0, 1.0);
        return true;
    };
    for (int i = 1; i < n; ++i) {
        const Px* begin = w.pixels.data() + w.offsets[i];
        const Px* end = w.pixels.data() + w.offsets[i + 1];
        if (end - begin < min_area) continue;
        // Where the region meets the rim: each tool enters the picture there. Entries
        // are runs of rim pixels by angle about the field of view's centre.
        w.entries.clear();
        for (const Px* p = begin; p != end; ++p)
            if (rim_distance(p->x, p->y) <= touch)
                w.entries.push_back(
                    {std::atan2(p->y - w.fov_cy, p->x - w.fov_cx), double(p->x), double(p->y)});
        if (w.entries.empty()) {
            // Not entering from outside the picture: kept where it may be a tool's end
            // cut off by a band across the shaft ("Across a band", below).
            Floating f;
            if (params_.bridge_widths > 0 && measure_floating(begin, end, f))
                w.floating.push_back(f);
            continue;
        }
        std::sort(w.entries.begin(), w.entries.end(),
                  [](const RimPixel& a, const RimPixel& b) { return a.angle < b.angle; });
        // Runs of entry pixels: a gap along the rim longer than `touch` starts a new one.
        const double gap = touch / std::max(1.0, w.fov_r);
        w.runs.clear();
        std::size_t first = 0;
        for (std::size_t k = 1; k <= w.entries.size(); ++k)
            if (k == w.entries.size() || w.entries[k].angle - w.entries[k - 1].angle > gap) {
                w.runs.push_back({first, k});
                first = k;
            }
        // The runs either side of -pi/pi are one entry: [last.first, size + first.second),
        // read modulo the entry count.
        if (w.runs.size() > 1 &&
            w.entries.front().angle + 2 * M_PI - w.entries.back().angle <= gap) {
            w.runs.front() = {w.runs.back().first, w.entries.size() + w.runs.front().second};
            w.runs.pop_back();
        }
        auto run_size = [](const std::pair<std::size_t, std::size_t>& r) {
            return r.second - r.first;
        };
        std::sort(w.runs.begin(), w.runs.end(),
                  [&](const auto& a, const auto& b) { return run_size(a) > run_size(b); });
        // A second entry much narrower than the first is a jaw reaching near the rim,
        // not another shaft coming in (a 5 mm shaft is half a 10 mm one).
        while (w.runs.size() > kMaxTools ||
               (w.runs.size() > 1 &&
                run_size(w.runs.back()) < params_.min_entry_ratio * run_size(w.runs.front())))
            w.runs.pop_back();

        const std::size_t lines = w.runs.size();
        std::array<Line, kMaxTools> line{};
        double n_all = 0, l1 = 0, l2 = 0;
        Line whole;
        fit_axis(
            begin, end, [](const Px*) { return true; }, whole, n_all, l1, l2);
        w.owner.assign(static_cast<std::size_t>(end - begin), 0);
        std::array<Point2, kMaxTools> entry{};
        for (std::size_t j = 0; j < lines; ++j) {
            double m = 0;
            for (std::size_t k = w.runs[j].first; k < w.runs[j].second; ++k) {
                const RimPixel& e = w.entries[k % w.entries.size()];
                entry[j].x += e.x, entry[j].y += e.y, m += 1;
            }
            entry[j] = {entry[j].x / m, entry[j].y / m};
        }
        // Two tracked tools in one region (touching or crossing): each entry goes to
        // the track that came in nearest to it, and each pixel to the tool whose
        // predicted shaft (entry to predicted tip, a segment, so a jaw beyond the other
        // tool's tip stays with its own tool) is nearer. In px, not in widths: a wide
        // tool's open jaws would otherwise claim the thin tool's tip.
        std::array<int, kMaxTools> run_track{-1, -1};
        if (lines > 1 && two_tracks) {
            auto d = [&](std::size_t j, std::size_t t) {
                return std::hypot(entry[j].x - w.tracks[t].rim_end.x,
                                  entry[j].y - w.tracks[t].rim_end.y);
            };
            const bool straight = d(0, 0) + d(1, 1) <= d(0, 1) + d(1, 0);
            run_track = {straight ? 0 : 1, straight ? 1 : 0};
            const Point2 tip0 = predicted[run_track[0]], tip1 = predicted[run_track[1]];
            for (const Px* p = begin; p != end; ++p)
                w.owner[p - begin] = segment_distance(entry[1], tip1, p->x, p->y) <
                                     segment_distance(entry[0], tip0, p->x, p->y);
        } else if (lines > 1) {
            // Two tools, not both tracked yet: k-lines, each started at its entry and
            // aimed at the region's centre, then refitted to the pixels nearer to it
            // than to the other.
            for (std::size_t j = 0; j < lines; ++j) {
                const double dx = whole.px - entry[j].x, dy = whole.py - entry[j].y,
                             d = std::max(1e-9, std::hypot(dx, dy));
                line[j] = {entry[j].x, entry[j].y, dx / d, dy / d};
            }
            for (int iter = 0; iter < 6; ++iter) {
                for (const Px* p = begin; p != end; ++p) {
                    std::uint8_t best = 0;
                    for (std::size_t j = 1; j < lines; ++j)
                        if (line[j].distance(p->x, p->y) < line[best].distance(p->x, p->y))
                            best = static_cast<std::uint8_t>(j);
                    w.owner[p - begin] = best;
                }
                for (std::size_t j = 0; j < lines; ++j) {
                    double nj, a1, a2;
                    Line fitted;
                    if (fit_axis(
                            begin, end, [&](const Px* p) { return w.owner[p - begin] == j; },
                            fitted, nj, a1, a2))
                        line[j] = fitted;
                }
            }
        } else {
            line[0] = whole;
        }
        for (std::size_t j = 0; j < lines; ++j) {
            auto mine = [&](const Px* p) { return w.owner[p - begin] == j; };
            double nj = 0, a1 = 0, a2 = 0;
            Line axis;
            if (!fit_axis(begin, end, mine, axis, nj, a1, a2) ||
                nj < (lines > 1 ? 0.5 : 1.0) * min_area)
                continue;
            if (run_track[j] >= 0) {
                // A tracked tool sharing its region: its shaft keeps the predicted
                // direction from its entry (a tool turns a fraction of a degree per
                // frame; the shared region's shape says little about it).
                const double a = w.tracks[run_track[j]].angle.position() * M_PI / 180.0;
                axis = {entry[j].x, entry[j].y, -std::cos(a), -std::sin(a)};
            } else if (std::sqrt(a1 / a2) < params_.min_elongation) {
                continue;
            }
            // A tracked tool's end is not looked for under the other tool's predicted
            // shaft (half its width, and the blur's 1.5 px, about the segment from its
            // entry to its tip): the pixels there show the other tool, whichever lies
            // on top; nor further than its own width from its own axis (a straight tool
            // ends on its axis; what lies aside is the other tool's jaw).
            const int other = run_track[j] >= 0 ? run_track[1 - j] : -1;
            auto hidden = [&](const Px* p) {
                if (other < 0) return false;
                const double lateral =
                    std::abs((p->x - axis.px) * axis.uy - (p->y - axis.py) * axis.ux);
                return lateral > w.tracks[run_track[j]].width ||
                       segment_distance(entry[1 - j], predicted[other], p->x, p->y) <
                           0.5 * w.tracks[other].width + 1.5;
            };
            const AxisSpan span = span_along(
                begin, end, axis, mine, [&](const Px* p) { return !hidden(p); }, w.prob, w.raw,
                params_.threshold);
            const double lo = span.lo, psum = span.psum, solid = span.solid;
            const bool end_hidden = other >= 0 && span.hi_seen > lo && span.hi_seen < span.hi;
            const double hi = end_hidden ? span.hi_seen : span.hi;
            const double band = std::max(1.0, 0.03 * (hi - lo));
            const double mid = 0.5 * (lo + hi);
            const AxisEnds ends = ends_along(
                begin, end, axis, mine, [&](const Px* p) { return !(end_hidden && hidden(p)); }, lo,
                hi, band, mid);
            const Point2 e_lo = ends.lo, e_hi = ends.hi;
            const double half_lo = ends.before_mid;
            const double d_lo = rim_distance(e_lo.x, e_lo.y), d_hi = rim_distance(e_hi.x, e_hi.y);
            if (std::min(d_lo, d_hi) > touch) continue;  // this part does not reach the rim
            // Both ends at the rim: it lies along the edge of the picture (a caption
            // band, the rim's own glare) instead of coming in through it.
            if (std::max(d_lo, d_hi) <= touch) continue;
            Candidate c;
            c.area = nj;
            c.length = std::max(1.0, hi - lo);
            c.width = nj / c.length;
            // The shaft alone (the half towards the rim; the jaws are narrower).
            c.shaft_width = (d_lo > d_hi ? nj - half_lo : half_lo) / (0.5 * c.length);
            c.tip = d_lo > d_hi ? e_lo : e_hi;
            c.rim_end = d_lo > d_hi ? e_hi : e_lo;
            // The silhouette edges of the shaft half: per slice along the axis, the
            // outermost pixel on each side; a line fitted to each side (perspective
            // makes them converge, which the 3-D pose needs).
            constexpr int kSlices = 16;
            std::array<double, kSlices> s_min, s_max;
            s_min.fill(std::numeric_limits<double>::max());
            s_max.fill(-std::numeric_limits<double>::max());
            const bool rim_high = d_lo > d_hi;
            const double t0 = rim_high ? mid : lo, t1 = rim_high ? hi : mid;
            for (const Px* p = begin; p != end; ++p)
                if (mine(p)) {
                    const double t = (p->x - axis.px) * axis.ux + (p->y - axis.py) * axis.uy;
                    if (t < t0 || t >= t1) continue;
                    const int k =
                        std::min(kSlices - 1, static_cast<int>((t - t0) / (t1 - t0) * kSlices));
                    const double o = -(p->x - axis.px) * axis.uy + (p->y - axis.py) * axis.ux;
                    s_min[k] = std::min(s_min[k], o - 0.5), s_max[k] = std::max(s_max[k], o + 0.5);
                }
            auto fit_side = [&](const std::array<double, kSlices>& side, Segment& out) {
                double n = 0, st = 0, so = 0, stt = 0, sto = 0;
                for (int k = 0; k < kSlices; ++k) {
                    if (std::abs(side[k]) > 1e300) continue;
                    const double t = t0 + (k + 0.5) * (t1 - t0) / kSlices;
                    n += 1, st += t, so += side[k], stt += t * t, sto += t * side[k];
                }
                if (n < 3) return false;
                const double den = n * stt - st * st;
                const double slope = std::abs(den) > 1e-9 ? (n * sto - st * so) / den : 0,
                             icpt = (so - slope * st) / n;
                auto at = [&](double t) {
                    const double o = icpt + slope * t;
                    return Point2{axis.px + t * axis.ux - o * axis.uy,
                                  axis.py + t * axis.uy + o * axis.ux};
                };
                out = {at(lo), at(hi)};
                return true;
            };
            c.has_edges = run_track[j] < 0 && fit_side(s_min, c.e1) && fit_side(s_max, c.e2);
            c.confidence = std::clamp(psum / nj / 255.0, 0.0, 1.0);
            // A tool is solidly tool-coloured before the smoothing; specular glints on wet
            // tissue are speckle that the blur joins up into a region.
            c.solid = solid >= params_.min_solid_fraction * nj;
            c.split = lines > 1;
            c.end_hidden = end_hidden;
            c.track = run_track[j];
            c.axis_deg = c.track >= 0 ? std::remainder(w.tracks[c.track].angle.position(), 360.0)
                                      : std::atan2(c.rim_end.y - c.tip.y, c.rim_end.x - c.tip.x) *
                                            180.0 / M_PI;
            if (params_.tip_axis && c.track < 0 && lines == 1) c.axis_deg = tip_axis(begin, end, c);
            w.candidates.push_back(c);
        }
    }
    // Across a band (docs/tracking.md, "Across a band"): a marker ring or a crossing
    // instrument cuts a shaft in two, the part with the jaws off the rim. A floating
    // region is that tool's end when the line of its axis, beyond one end, crosses a
    // gap of at most `bridge_widths` widths below even odds and then runs on to the rim
    // over tool-coloured pixels (at least kBridgeFill of the points: the most likely
    // within half a width aside). It is then a tool from its other end to the rim, in
    // place of the region it continues (a region whose tip lies along that line).
    const std::size_t region_count = w.candidates.size();
    bool bridged = false;  // a tool the regions missed: rank by support, as for a bar
    for (const Floating& f : w.floating) {
        const int half = std::max(1, static_cast<int>(std::lround(0.5 * f.width)));
        auto likely = [&](double x, double y, double ux, double uy) {
            int best = 0;
            for (int o = -half; o <= half; ++o) {
                const int xi = std::clamp(static_cast<int>(std::lround(x - o * uy)), 0, W - 1),
                          yi = std::clamp(static_cast<int>(std::lround(y + o * ux)), 0, H - 1);
                best = std::max<int>(best, w.prob.at<std::uint8_t>(yi, xi));
            }
            return best >= params_.threshold;
        };
        int through = -1;  // the end the line leaves by towards the rim
        Point2 rim_point;
        for (int k = 0; k < 2; ++k) {
            const double ux = k == 1 ? f.ux : -f.ux, uy = k == 1 ? f.uy : -f.uy;
            const Point2 from = f.ends[k];
            int state = 0, gap = 0, points = 0, good = 0;  // 0 own end, 1 gap, 2 beyond
            bool reached = false;
            Point2 at;
            for (int step = 1; step < W + H; ++step) {
                at = {from.x + step * ux, from.y + step * uy};
                const double x = at.x, y = at.y;
                if (x < 0 || y < 0 || x > W - 1 || y > H - 1) break;
                if (rim_distance(x, y) <= touch) {
                    reached = true;
                    break;
                }
                const bool lit = likely(x, y, ux, uy);
                if (state == 0 && !lit) state = 1;
                if (state == 1 && lit) state = 2;
                if (state == 1 && ++gap > params_.bridge_widths * f.width) break;
                if (state == 2) ++points, good += lit;
            }
            if (!reached || points < 2 * f.width || good < kBridgeFill * points) continue;
            if (through >= 0) {  // tool-coloured both ways: not a tool's end
                through = -1;
                break;
            }
            through = k;
            rim_point = at;  // where the line comes within `touch` of the rim
        }
        if (through < 0) continue;
        Candidate c;
        c.tip = f.ends[1 - through];
        c.rim_end = rim_point;
        c.length = std::hypot(c.rim_end.x - c.tip.x, c.rim_end.y - c.tip.y);
        c.width = c.shaft_width = f.width;
        c.area = f.area;  // ranks by what was seen; a region it continues adds its own
        c.confidence = f.confidence;
        c.axis_deg = std::atan2(c.rim_end.y - c.tip.y, c.rim_end.x - c.tip.x) * 180.0 / M_PI;
        // The region beyond the band is this tool's shaft: replaced (the first such),
        // or dropped (any other).
        bool placed = false;
        for (std::size_t k = 0; k < region_count; ++k) {
            Candidate& r = w.candidates[k];
            if (r.area <= 0 || r.split ||
                std::abs(std::remainder(r.axis_deg - c.axis_deg, 180.0)) > kBridgeTurnDeg ||
                segment_distance(f.ends[through], c.rim_end, r.tip.x, r.tip.y) >
                    2 * std::max(r.width, c.width))
                continue;
            if (placed) {
                r.area = 0;  // removed below
            } else {
                const double area = r.area + c.area;
                r = c;
                r.area = area;
                placed = true;
            }
        }
        if (!placed) {
            w.candidates.push_back(c);
            bridged = true;
        }
    }
    std::erase_if(w.candidates, [](const Candidate& c) { return c.area <= 0; });
    // Identities: candidates to live tracks, the assignment of least summed cost (tip
    // distance to the prediction in widths, plus the turn of the axis in units of
    // kAngleGateDeg); a candidate cut out by a track's prediction belongs to it.
    auto pair_cost = [&](const Candidate& c, std::size_t t) {
        const Track& tr = w.tracks[t];
        if (c.track >= 0 && static_cast<std::size_t>(c.track) != t) return 1e9;
        const double a = c.axis_deg;
        return std::hypot(c.tip.x - tr.x.position(), c.tip.y - tr.y.position()) /
                   std::max(2.0, tr.width) +
               angle_diff_deg(a, tr.angle.position()) / kAngleGateDeg;
    };
    // No track is born from a region short of solid; it may only continue one.
    std::erase_if(w.candidates, [&](const Candidate& c) {
        if (c.solid) return false;
        for (std::size_t t = 0; t < nt; ++t)
            if (w.tracks[t].id >= 0 && pair_cost(c, t) <= kContinuationCost) return false;
        return true;
    });
    // Bars of tool likelihood from the rim (docs/tracking.md, "Bars from the rim"): a
    // region along one is that tool (its support: its own length or the bar's); a long
    // bar along no region is a tool the regions missed (a dark shaft in shadow). Where
    // such a bar is added, the tools with the longest straight support win, not the
    // largest.
    bool added = bridged;
    // A region's own length is its support; a part of a region two tools share keeps
    // its place (its length is cut by the other tool, and it has a track).
    for (Candidate& c : w.candidates)
        c.support = c.split ? std::numeric_limits<double>::max() : c.length;
    if (params_.rim_bars) {
        const std::span<const detail::RimBar> bars =
            w.bars.search(w.prob.ptr<std::uint8_t>(0), w.eroded.ptr<std::uint8_t>(0), w.prob.step);
        const std::size_t regions = w.candidates.size();
        for (const detail::RimBar& b : bars) {
            const double axis = std::atan2(b.rim.y - b.tip.y, b.rim.x - b.tip.x) * 180.0 / M_PI;
            bool along = false;
            for (std::size_t k = 0; k < regions; ++k) {
                Candidate& c = w.candidates[k];
                // Along it: within 20 degrees, and either tip within two widths of the
                // other's shaft (a bar can stop short of the jaws, a region at them).
                const double near = 2 * std::max(b.width, c.width);
                if (std::abs(std::remainder(c.axis_deg - axis, 180.0)) > 20.0 ||
                    (segment_distance(b.rim, b.tip, c.tip.x, c.tip.y) > near &&
                     segment_distance(c.rim_end, c.tip, b.tip.x, b.tip.y) > near))
                    continue;
                c.support = std::max(c.support, b.length);
                along = true;
            }
            if (along || b.length < params_.bar_min_length_fraction * W ||
                b.frames < params_.bar_min_frames)
                continue;
            Candidate c;
            added = true;
            c.support = c.length = b.length;
            c.width = c.shaft_width = b.width;
            c.area = b.length * b.width;
            c.tip = b.tip;
            c.rim_end = b.rim;
            c.axis_deg = axis;
            c.confidence = std::clamp(b.level / 255.0, 0.0, 1.0);
            w.candidates.push_back(c);
        }
    }
    std::sort(w.candidates.begin(), w.candidates.end(),
              [added](const Candidate& a, const Candidate& b) {
                  if (added && a.support != b.support) return a.support > b.support;
                  return a.area > b.area;
              });
    const std::size_t found = std::min({w.candidates.size(), params_.max_tools, kMaxTools});
    std::array<int, kMaxTools> track_of{-1, -1};
    double best = std::numeric_limits<double>::max();
    for (int perm = 0; perm < (nt < 2 ? 1 : 2); ++perm) {
        std::array<int, kMaxTools> pick{-1, -1};
        double cost = 0;
        for (std::size_t k = 0; k < found; ++k) {
            const std::size_t t = perm == 0 ? k : (nt - 1 - k);
            if (t >= nt || w.tracks[t].id < 0) {
                cost += 1e6;  // a new track: dearer than any match that is allowed
                continue;
            }
            pick[k] = static_cast<int>(t);
            cost += pair_cost(w.candidates[k], t);
        }
        if (cost < best) best = cost, track_of = pick;
    }
    std::array<bool, kMaxTools> used{false, false}, fresh{false, false};
    for (std::size_t k = 0; k < found; ++k)
        if (track_of[k] >= 0) used[track_of[k]] = true;
    for (std::size_t k = 0; k < found; ++k) {
        if (track_of[k] >= 0) continue;
        // A free track, else (both live but unmatched) the unused one.
        for (int pass = 0; pass < 2 && track_of[k] < 0; ++pass)
            for (std::size_t t = 0; t < nt && track_of[k] < 0; ++t)
                if (!used[t] && (pass == 1 || w.tracks[t].id < 0)) {
                    track_of[k] = static_cast<int>(t), used[t] = true, fresh[t] = true;
                    w.tracks[t] = Track{};
                    w.tracks[t].id = next_id_++;
                }
    }
    for (std::size_t t = 0; t < nt; ++t)
        if (!used[t] && w.tracks[t].id >= 0 && ++w.tracks[t].missed > params_.keep_frames)
            w.tracks[t] = Track{};

    const double inv = 1.0 / w.scale;
    std::size_t count = 0;
    for (std::size_t k = 0; k < found; ++k) {
        const Candidate& c = w.candidates[k];
        Track& t = w.tracks[track_of[k]];
        const double measured_deg = c.axis_deg;
        Point2 tip = c.tip;  // the measurement, or where it says the tip is at least
        bool coast = false;
        if (fresh[track_of[k]]) {
            t.x.reset(tip.x), t.y.reset(tip.y), t.angle.reset(measured_deg);
        } else {
            const double pa = t.angle.position(),
                         za = pa + std::remainder(measured_deg - pa, 360.0);
            if (c.split && t.coasted < params_.max_coast_frames) {
                // Where this tool runs under the other one's predicted shaft, the end
                // seen is where it disappears: the tip is at least that far from the
                // rim, not nearer (the lateral position still counts).
                if (c.end_hidden) {
                    const double ux = std::cos(pa * M_PI / 180.0), uy = std::sin(pa * M_PI / 180.0);
                    double along = (tip.x - predicted[track_of[k]].x) * ux +
                                   (tip.y - predicted[track_of[k]].y) * uy;
                    // At most two widths of the other tool on: a hidden end lies under
                    // its shaft, not wherever a prediction on a wrong speed has gone.
                    const double under = 2 * std::max(w.tracks[1 - track_of[k]].width, t.width);
                    if (along > 0) {
                        along = std::min(along, under);
                        tip.x -= along * ux, tip.y -= along * uy;
                        // The end seen says nothing of the speed: the prediction's own
                        // fades (a hidden tip at rest is not carried on by it).
                        t.x.damp_velocity(kHiddenVelocityDamping);
                        t.y.damp_velocity(kHiddenVelocityDamping);
                    }
                }
                // A part of a shared region that jumped away from the prediction belongs
                // to the other tool (a jaw across its shaft); the track coasts. The gate:
                // at least a width, at most two (the book's tolerance) however long it coasted.
                const double s = std::sqrt(
                    std::max(t.x.innovation_var(kTipNoise), t.y.innovation_var(kTipNoise)));
                const double gate = std::clamp(kGateSigmas * s, t.width, 2 * t.width);
                coast = std::hypot(tip.x - t.x.position(), tip.y - t.y.position()) > gate ||
                        std::abs(za - pa) > kAngleGateDeg;
            }
            if (!coast) {
                t.x.update(tip.x, kTipNoise), t.y.update(tip.y, kTipNoise);
                // In a shared region the axis is the prediction itself, which nothing
                // measured corrects: at the rate it had on entering, it turned on about
                // its entry, through the tissue, while both tools rested. So it keeps no
                // rate there (docs/tracking.md, "A shared tool does not turn").
                if (c.track < 0)
                    t.angle.update(za, kAngleNoise);
                else
                    t.angle.damp_velocity(0.0);
            }
        }
        t.missed = 0;
        t.coasted = coast ? t.coasted + 1 : 0;
        if (!coast) {
            t.rim_end = c.rim_end;
            if (!c.split || t.width <= 0) t.width = c.width;
            t.confidence = c.confidence;
        }
        if (coast && rim_distance(t.tip().x, t.tip().y) <= 0) {
            // A prediction that left the picture is no tool: a tip is where a tool ends
            // inside the view (a tool leaving, or a prediction run off on a wrong speed).
            t = Track{};
            continue;
        }
        ToolEstimate& e = out[count++];
        e = ToolEstimate{};
        e.id = t.id;
        e.present = true;
        if (coast) {
            // The prediction, at half the last confidence; no edges, so no 3-D pose.
            const double a = t.angle.position() * M_PI / 180.0, ux = std::cos(a), uy = std::sin(a);
            tip = t.tip();
            e.tip = {tip.x * inv, tip.y * inv};
            e.head = {(tip.x + ux * params_.head_widths * t.width) * inv,
                      (tip.y + uy * params_.head_widths * t.width) * inv};
            e.axis_deg = std::remainder(t.angle.position(), 360.0);
            e.width_px = t.width * inv;
            e.confidence = 0.5 * t.confidence;
            e.edges.midline = {e.tip, {t.rim_end.x * inv, t.rim_end.y * inv}};
            continue;
        }
        const double dx = std::cos(c.axis_deg * M_PI / 180.0),
                     dy = std::sin(c.axis_deg * M_PI / 180.0), len = 1.0;
        e.tip = {tip.x * inv, tip.y * inv};
        e.head = {(tip.x + dx / len * params_.head_widths * c.width) * inv,
                  (tip.y + dy / len * params_.head_widths * c.width) * inv};
        e.axis_deg = c.axis_deg;
        e.width_px = c.width * inv;
        e.confidence = c.confidence;
        e.edges.found = c.has_edges;
        e.edges.width_px = c.shaft_width * inv;
        // The coarse edges (analysis scale) refined on the full-resolution frame, from
        // the tip's end: the 3-D pose's depth rests on the apparent width, where a
        // pixel is worth about 4 % of the distance.
        auto scaled = [inv](const Segment& s) {
            return Segment{{s.a.x * inv, s.a.y * inv}, {s.b.x * inv, s.b.y * inv}};
        };
        const bool tip_at_a = std::hypot(c.e1.a.x - c.tip.x, c.e1.a.y - c.tip.y) <
                              std::hypot(c.e1.b.x - c.tip.x, c.e1.b.y - c.tip.y);
        auto from_tip = [tip_at_a](Segment s) { return tip_at_a ? s : Segment{s.b, s.a}; };
        if (c.has_edges) {
            // Only the shaft: from a width past the head (the jaws are narrower and
            // would pull the lines together, making the tool look further away).
            const double shaft_from =
                std::clamp((params_.head_widths + 1) * c.width / c.length, 0.2, 0.8);
            e.edges.e1 = refine_edge(full, from_tip(scaled(c.e1)), shaft_from, 1.0, 2.5 * inv);
            e.edges.e2 = refine_edge(full, from_tip(scaled(c.e2)), shaft_from, 1.0, 2.5 * inv);
        }
        e.edges.midline = {e.tip, {c.rim_end.x * inv, c.rim_end.y * inv}};
    }
    return count;
}

}  // namespace endotower::vision
