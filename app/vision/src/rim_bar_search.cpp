// RimBarSearch (rim_bar_search.hpp).
#include "rim_bar_search.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::vision::detail {

namespace {

constexpr double kStepDeg = 180.0 / RimBarSearch::kOrientations;
constexpr std::uint8_t kValid = 1, kGood = 16;  // per width index: << index

// Two bars are one where their directions differ by less than 20 degrees and either tip
// lies within two widths (+ 4 px) of the other's segment.
bool same_bar(const RimBar& a, const RimBar& b) {
    if (std::abs(std::remainder(a.inward_deg - b.inward_deg, 360.0)) >= 20.0) return false;
    const double near = 2 * std::max(a.width, b.width) + 4;
    return segment_distance(a.rim, a.tip, b.tip.x, b.tip.y) < near ||
           segment_distance(b.rim, b.tip, a.tip.x, a.tip.y) < near;
}

// Narrows [lo, hi] to the steps p at which o + p d rounds to a pixel of a picture `size`
// wide ([-0.5, size - 0.5]), widened by `margin` either side; empty (lo > hi) when none.
void clip_to_picture(double o, double d, int size, double margin, double& lo, double& hi) {
    if (std::abs(d) < 1e-12) {
        if (o < -0.5 || o > size - 0.5) lo = 1, hi = 0;
        return;
    }
    const double a = (-0.5 - o) / d, b = (size - 0.5 - o) / d;
    lo = std::max(lo, std::min(a, b) - margin), hi = std::min(hi, std::max(a, b) + margin);
}

}  // namespace

// A line of the scan: point(c + j, t) = origin + (c + j) n + t d, in half-size px.
struct RimBarSearch::Line {
    double ox, oy, dx, dy, nx, ny;
    int column;
};

RimBarSearch::Line RimBarSearch::line(int orientation, int column) const {
    const double a = orientation * kStepDeg * M_PI / 180.0;
    const double dx = std::cos(a), dy = std::sin(a), nx = -dy, ny = dx;
    const double half = d_ / 2.0, cx = w_ / 2.0, cy = h_ / 2.0;
    return {cx - half * nx - half * dx, cy - half * ny - half * dy, dx, dy, nx, ny, column};
}

void RimBarSearch::configure(int width, int height) {
    w_ = std::max(1, width / 2), h_ = std::max(1, height / 2);
    d_ = static_cast<int>(std::ceil(std::hypot(w_, h_))) + 2;
    const auto cells = static_cast<std::size_t>(d_) * d_;
    prob_.assign(static_cast<std::size_t>(w_) * h_, 0);
    lit_.assign(prob_.size(), 0);
    flags_.assign(cells, 0);
    contrast_.assign(cells * params_.widths.size(), 0);
    col_first_.assign(static_cast<std::size_t>(d_) * params_.widths.size(), d_);
    col_last_.assign(col_first_.size(), -1);
    sum_p_.assign(d_ + 1, 0), sum_l_.assign(d_ + 1, 0);
    kept_.clear(), scanned_.clear(), out_.clear();
    kept_.reserve(kMaxBars + kOrientations * kKeptPerScan);
    scanned_.reserve(static_cast<std::size_t>(d_) * params_.widths.size() * 2);
    out_.reserve(kMaxBars);
    next_ = 0;
}

// The run along one line, given each point's flags and contrast in scan order (from the
// rim inwards): the bar from its first lit point, or false.
// `from`: where to start looking for the first lit point (a point known to be before it).
template <typename PointAt>
static bool run_bar(int from, int n, int width, int width_index, const RimBarParams& p,
                    double touch, double min_length, PointAt point_at, int& r0_out, int& end_out,
                    double& score, double& level) {
    const int gap = std::max(2, width);
    int r0 = -1, rs = -1, end = -1, count = 0, bad = 0;
    score = level = 0;
    for (int s = from; s < n; ++s) {
        std::uint8_t f;
        int c, lv;
        point_at(s, f, c, lv);
        if (r0 < 0) {
            if (!(f & (kValid << width_index))) continue;
            r0 = s;
        }
        const bool good = f & (kGood << width_index);
        if (rs < 0) {
            if (s - r0 > touch) return false;  // no bar within reach of the rim
            if (good) rs = end = s, count = 1, score = c, level = lv;
            continue;
        }
        if (good) {
            end = s, ++count, bad = 0, score += c, level += lv;
        } else if (++bad > gap) {
            break;
        }
    }
    if (rs < 0 || end - r0 < min_length || count < p.min_fill * (end - rs + 1)) return false;
    r0_out = r0, end_out = end, level /= count;
    return true;
}

bool RimBarSearch::measure(const Line& l, int wi, bool reverse, RimBar& out) const {
    const int w = params_.widths[wi], off = (w + 1) / 2 + 1 + w / 2;
    const int lo = -off - w / 2, hi = off - w / 2 + w - 1;  // the footprint, across
    // The scan's sampling (16.16 fixed point from the row's start), so that a line
    // measured again reads the pixels its scan read.
    constexpr double kOne = 65536.0;
    const auto fnx = static_cast<std::int64_t>(std::llround(l.nx * kOne)),
               fny = static_cast<std::int64_t>(std::llround(l.ny * kOne));
    auto point_at = [&](int s, std::uint8_t& f, int& contrast, int& level) {
        const int t = reverse ? d_ - 1 - s : s;
        const auto fx0 = static_cast<std::int64_t>(std::floor((l.ox + t * l.dx + 0.5) * kOne)),
                   fy0 = static_cast<std::int64_t>(std::floor((l.oy + t * l.dy + 0.5) * kOne));
        int strip = 0, left = 0, right = 0, lit = 0;
        for (int j = lo; j <= hi; ++j) {
            const std::int64_t c = l.column + j;
            const auto xi = static_cast<int>((fx0 + c * fnx) >> 16),
                       yi = static_cast<int>((fy0 + c * fny) >> 16);
            if (xi < 0 || yi < 0 || xi >= w_ || yi >= h_) continue;
            const std::size_t i = static_cast<std::size_t>(yi) * w_ + xi;
            lit += lit_[i];
            const int v = prob_[i];
            if (j >= -w / 2 && j < -w / 2 + w) strip += v;
            if (j >= lo && j < lo + w) left += v;
            if (j > hi - w) right += v;
        }
        f = 0, contrast = level = 0;
        if (lit < hi - lo + 1) return;
        f = kValid << wi;
        const int S = strip / w, C = S - std::max(left, right) / w;
        if (S >= params_.min_level && C >= params_.min_contrast)
            f |= kGood << wi, contrast = std::min(C, 255), level = S;
    };
    // Before the line's centre enters the picture no footprint is lit: start there.
    double t_in = 0, t_out = d_ - 1;
    clip_to_picture(l.ox + l.column * l.nx, l.dx, w_, 0, t_in, t_out);
    clip_to_picture(l.oy + l.column * l.ny, l.dy, h_, 0, t_in, t_out);
    if (t_in > t_out) return false;
    const int from = reverse ? std::max(0, d_ - 2 - static_cast<int>(std::ceil(t_out)))
                             : std::max(0, static_cast<int>(std::floor(t_in)) - 1);
    int r0 = 0, end = 0;
    double score = 0, level = 0;
    if (!run_bar(from, d_, w, wi, params_, params_.touch_fraction * w_,
                 params_.min_length_fraction * w_, point_at, r0, end, score, level))
        return false;
    auto at = [&](int s) {
        const int t = reverse ? d_ - 1 - s : s;
        // Half-size pixel (x, y) covers analysis pixels 2x, 2x + 1: centre 2x + 0.5.
        return Point2{2 * (l.ox + l.column * l.nx + t * l.dx) + 0.5,
                      2 * (l.oy + l.column * l.ny + t * l.dy) + 0.5};
    };
    out.rim = at(r0), out.tip = at(end);
    out.width = 2.0 * w, out.length = 2.0 * (end - r0), out.score = score, out.level = level;
    out.inward_deg = std::atan2(out.tip.y - out.rim.y, out.tip.x - out.rim.x) * 180.0 / M_PI;
    return true;
}

void RimBarSearch::scan(int orientation) {
    const Line base = line(orientation, 0);
    const std::size_t nw = params_.widths.size();
    // Per width and column, the first and last row with a lit footprint (none: d_, -1),
    // so that the runs below start there instead of walking the unlit part.
    std::fill(col_first_.begin(), col_first_.end(), d_);
    std::fill(col_last_.begin(), col_last_.end(), -1);
    // Every point's flags and contrast, row by row: the row's samples, their running
    // sums, then per width the strip, its flanks and the lit footprint from the sums.
    for (int t = 0; t < d_; ++t) {
        const double x0 = base.ox + t * base.dx, y0 = base.oy + t * base.dy;
        // The columns whose point lies in the picture (a margin of one for rounding).
        double c_lo = 0, c_hi = d_ - 1;
        clip_to_picture(x0, base.nx, w_, 1, c_lo, c_hi);
        clip_to_picture(y0, base.ny, h_, 1, c_lo, c_hi);
        const int first = std::max(0, static_cast<int>(std::floor(c_lo))),
                  last = std::min(d_ - 1, static_cast<int>(std::ceil(c_hi)));
        // Nearest pixel by 16.16 fixed point steps (the shift floors negatives too).
        constexpr double kOne = 65536.0;
        const auto fx0 = static_cast<std::int64_t>(std::floor((x0 + 0.5) * kOne)),
                   fy0 = static_cast<std::int64_t>(std::floor((y0 + 0.5) * kOne));
        const auto fnx = static_cast<std::int64_t>(std::llround(base.nx * kOne)),
                   fny = static_cast<std::int64_t>(std::llround(base.ny * kOne));
        // Only [first, last] is sampled and summed: the columns outside it are unlit, so
        // no footprint that reaches them is valid (below).
        std::uint8_t* flags = flags_.data() + static_cast<std::size_t>(t) * d_;
        std::fill(flags, flags + d_, 0);
        if (first > last) continue;
        sum_p_[first] = sum_l_[first] = 0;
        for (int c = first; c <= last; ++c) {
            const auto xi = static_cast<int>((fx0 + c * fnx) >> 16),
                       yi = static_cast<int>((fy0 + c * fny) >> 16);
            int p = 0, l = 0;
            if (xi >= 0 && yi >= 0 && xi < w_ && yi < h_) {
                const std::size_t i = static_cast<std::size_t>(yi) * w_ + xi;
                p = prob_[i], l = lit_[i];
            }
            sum_p_[c + 1] = sum_p_[c] + p;
            sum_l_[c + 1] = sum_l_[c] + l;
        }
        for (std::size_t wi = 0; wi < nw; ++wi) {
            const int w = params_.widths[wi], off = (w + 1) / 2 + 1 + w / 2;
            const int lo = -off - w / 2, hi = off - w / 2 + w - 1;
            // Read only where the point is good (run_bar), so not cleared.
            std::uint8_t* contrast = contrast_.data() + (wi * d_ + t) * d_;
            int* col_first = col_first_.data() + wi * d_;
            int* col_last = col_last_.data() + wi * d_;
            auto box = [&](int from) { return sum_p_[from + w] - sum_p_[from]; };
            // Footprints inside [first, last] only.
            for (int c = first - lo; c <= last - hi; ++c) {
                if (sum_l_[c + hi + 1] - sum_l_[c + lo] < hi - lo + 1) continue;
                flags[c] |= kValid << wi;
                if (col_first[c] == d_) col_first[c] = t;
                col_last[c] = t;
                const int S = box(c - w / 2) / w;
                if (S < params_.min_level) continue;
                const int C = S - std::max(box(c + lo), box(c + hi - w + 1)) / w;
                if (C < params_.min_contrast) continue;
                flags[c] |= kGood << wi;
                contrast[c] = static_cast<std::uint8_t>(std::min(C, 255));
            }
        }
    }
    // Per line, width and way in: the bar, if any; the strongest few of this orientation.
    scanned_.clear();
    for (int c = 0; c < d_; ++c)
        for (std::size_t wi = 0; wi < nw; ++wi) {
            if (col_first_[wi * d_ + c] == d_) continue;  // no lit footprint on this line
            for (const bool reverse : {false, true}) {
                auto point_at = [&](int s, std::uint8_t& f, int& contrast, int& level) {
                    const int t = reverse ? d_ - 1 - s : s;
                    const std::size_t i = static_cast<std::size_t>(t) * d_ + c;
                    f = flags_[i];
                    contrast = contrast_[wi * d_ * d_ + i];
                    level = 0;  // the level is measured again below, for the kept ones only
                };
                int r0 = 0, end = 0;
                double score = 0, level = 0;
                const int from =
                    reverse ? d_ - 1 - col_last_[wi * d_ + c] : col_first_[wi * d_ + c];
                if (!run_bar(from, d_, params_.widths[wi], static_cast<int>(wi), params_,
                             params_.touch_fraction * w_, params_.min_length_fraction * w_,
                             point_at, r0, end, score, level))
                    continue;
                Kept k;
                k.orientation = orientation, k.column = c, k.width_index = static_cast<int>(wi);
                k.reverse = reverse;
                k.bar.score = score;
                scanned_.push_back(k);
            }
        }
    std::sort(scanned_.begin(), scanned_.end(),
              [](const Kept& a, const Kept& b) { return a.bar.score > b.bar.score; });
    // The strongest few, each a bar of its own; a bar seen before keeps its age.
    std::size_t taken = 0;
    for (std::size_t i = 0; i < scanned_.size() && taken < kKeptPerScan; ++i) {
        Kept& s = scanned_[i];
        if (!measure(line(orientation, s.column), s.width_index, s.reverse, s.bar)) continue;
        bool same = false;
        for (std::size_t j = 0; j < taken && !same; ++j) same = same_bar(scanned_[j].bar, s.bar);
        if (same) continue;
        for (const Kept& k : kept_)
            if (same_bar(k.bar, s.bar)) s.bar.frames = std::max(s.bar.frames, k.bar.frames);
        scanned_[taken++] = s;
    }
    std::erase_if(kept_, [orientation](const Kept& k) { return k.orientation == orientation; });
    for (std::size_t i = 0; i < taken; ++i) kept_.push_back(scanned_[i]);
}

std::span<const RimBar> RimBarSearch::search(const std::uint8_t* prob, const std::uint8_t* lit,
                                             std::size_t stride) {
    out_.clear();
    if (d_ == 0) return out_;
    // Half size: the mean of each 2 x 2 block; lit where all four are, not on the border.
    for (int y = 0; y < h_; ++y)
        for (int x = 0; x < w_; ++x) {
            const std::uint8_t* p = prob + 2 * y * stride + 2 * x;
            const std::uint8_t* l = lit + 2 * y * stride + 2 * x;
            const std::size_t i = static_cast<std::size_t>(y) * w_ + x;
            prob_[i] = static_cast<std::uint8_t>((p[0] + p[1] + p[stride] + p[stride + 1] + 2) / 4);
            const bool border = x == 0 || y == 0 || x == w_ - 1 || y == h_ - 1;
            lit_[i] = !border && l[0] && l[1] && l[stride] && l[stride + 1];
        }
    // The bars kept from earlier scans, measured again along their own lines.
    const int count = std::clamp(params_.orientations_per_frame, 1, kOrientations);
    auto scanned_now = [&](int o) { return (o - next_ + kOrientations) % kOrientations < count; };
    // A tool moves a little between scans: its line is looked for up to two columns aside.
    std::size_t still = 0;
    for (Kept& k : kept_) {
        if (scanned_now(k.orientation)) {
            kept_[still++] = k;
            continue;
        }
        // And turns a little: the neighbouring orientations' lines through its rim point
        // (past 180 degrees the way in turns round).
        bool found = false;
        RimBar b;
        Kept best = k;
        const Point2 rim{(k.bar.rim.x - 0.5) / 2, (k.bar.rim.y - 0.5) / 2};  // half-size px
        for (const int dor : {0, -1, 1}) {
            int o = k.orientation + dor;
            bool reverse = k.reverse;
            if (o < 0 || o >= kOrientations)
                o = (o + kOrientations) % kOrientations, reverse = !reverse;
            const Line l0 = line(o, 0);
            const int c0 =
                static_cast<int>(std::lround((rim.x - l0.ox) * l0.nx + (rim.y - l0.oy) * l0.ny));
            for (const int dc : {0, -1, 1})
                if (measure(line(o, c0 + dc), k.width_index, reverse, b) &&
                    (!found || b.score > best.bar.score))
                    found = true, best.bar = b, best.orientation = o, best.column = c0 + dc,
                    best.reverse = reverse;
        }
        if (found) best.bar.frames = k.bar.frames, kept_[still++] = best;
    }
    kept_.resize(still);
    for (int i = 0; i < count; ++i) scan((next_ + i) % kOrientations);
    next_ = (next_ + count) % kOrientations;
    // One bar per tool: the strongest of those within 20 degrees and two widths; only
    // those are kept for the next frames.
    std::sort(kept_.begin(), kept_.end(),
              [](const Kept& a, const Kept& b) { return a.bar.score > b.bar.score; });
    std::size_t n = 0;
    for (std::size_t i = 0; i < kept_.size() && n < kMaxBars; ++i) {
        bool same = false;
        for (std::size_t j = 0; j < n && !same; ++j)
            if (same_bar(kept_[j].bar, kept_[i].bar))
                same = true,
                kept_[j].bar.frames = std::max(kept_[j].bar.frames, kept_[i].bar.frames);
        if (!same) kept_[n++] = kept_[i];
    }
    kept_.resize(n);
    for (Kept& k : kept_) ++k.bar.frames, out_.push_back(k.bar);
    return out_;
}

}  // namespace endotower::vision::detail
