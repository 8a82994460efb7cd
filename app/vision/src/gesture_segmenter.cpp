#include "endotower/vision/gesture_segmenter.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <system_error>
#include <vector>

#include "endotower/app/helper_thread.hpp"
#include "endotower/vision/area_mean.hpp"
#include "endotower/vision/mask_ops.hpp"
#include "reduce_frame.hpp"
#include "wide_vectors.hpp"

namespace endotower::vision {

struct GestureSegmenter::Work {
    double scale = 1.0;
    AreaMean reduce;  // INTER_AREA, no allocation (factor <= 15: else cv::resize)
    // The per-pixel passes over the frame in bands of rows, the second on the helper
    // (`threads` = 2): the reduction where it is a block mean (each band's BlockMean
    // reads its own input rows: the same bytes), the grey values and their histograms,
    // and every pixel's tool probability (into `blurred`; cleared outside the lit field
    // once that is known).
    struct Band {
        int y0 = 0, y1 = 0;
        BlockMean reduce;
        std::vector<std::uint16_t> cells;  // one row's ToolLikelihood cells
        std::array<std::array<int, 256>, 4> hists{};
    };
    std::array<Band, 2> bands;
    int band_count = 1;
    bool band_reduce = false;                      // this frame's reduction is the bands'
    const hal::Frame* frame = nullptr;             // the frame the bands reduce
    const std::uint8_t* table = nullptr;           // the tool probability; null: not needed
    std::unique_ptr<app::HelperThread> helper;     // band 1, its share of the regions
    void run_band(Band& b);
    // part(*this, 1) on the helper (two bands) while the caller runs part(*this, 0).
    using Part = void (*)(Work&, int);
    Part part = nullptr;
    void share(Part p);
    MaskOps ops;
    std::array<int, 15> fov_rows{};  // the field-of-view element's rows as half-widths
    // The one-tool mask (`single_threshold`): the smoothed probability, its mask, regions.
    MaskOps single_ops;
    cv::Mat smoothed, single_binary, single_labels;
    // The mask whose regions measure_region() reads: `binary` or `single_binary`.
    // defer_one_tool: a region that enters once is only checked, not measured (the
    // first mask's pass with two masks).
    bool defer_one_tool = false;
    const MaskOps* mask_ops = nullptr;
    const cv::Mat* mask_binary = nullptr;
    const cv::Mat* mask_labels = nullptr;
    cv::Mat small, gray, blurred, lit, eroded, a, opened, binary, labels;
    cv::Mat large_element, small_element;
    struct Px {
        int x, y;
    };
    struct Region {
        int label, area;
    };
    std::vector<Region> regions;
    // One region's measurement: its tip, window, arms and features (two: with the
    // helper, the caller and it each take the next region in size order when free).
    struct RegionScratch {
        int label = 0;
        MaskOps distances;                // chamfer() alone
        ContourTracer tracer;             // the features' contours (window <= the analysis size)
        std::vector<std::uint32_t> dist;  // chamfer distances in the region's box
        std::vector<double> reach;        // per region pixel, its distance from the entry
        std::vector<Px> pixels, entries;
        cv::Mat window;
        GestureBlob blob;
    };
    std::array<RegionScratch, 2> scratch;
    // The regions handed out (the next one's index) and the blobs found, each with its
    // region's index: a thread takes no new region once kMaxBlobs are found, so with two
    // threads at most kMaxBlobs + 1 are.
    std::atomic<std::size_t> next_region{0};
    std::atomic<int> found_count{0}, found_slots{0};
    struct Found {
        std::size_t region = 0;
        GestureBlob blob;
    };
    std::array<Found, GestureSegmenter::kMaxBlobs + 1> found;
    // Takes regions until none is left or kMaxBlobs are found, measuring each into `s`.
    void measure_regions(RegionScratch& s);
    struct Field {  // this frame's lit field of view (analysis pixels), the rim distance
        double cx = 0, cy = 0, r = 0, touch = 0;
    } field;
    const GestureSegmenterParams* params = nullptr;
    // The region `s.label`'s blob into s.blob; false: no tool's tip (not entering from
    // outside, not elongated, no valid features).
    bool measure_region(RegionScratch& s);
    // Measures `regions` of the mask `b` (its regions `o`, labels `l`) on both threads;
    // the blobs found are found[0, n), in the order of `regions`.
    std::size_t measure_found(const MaskOps& o, const cv::Mat& b, const cv::Mat& l);
    // `blobs` (found[i] each's): each one-entry blob, only checked so far, measured on
    // the one-tool mask (`single_threshold`) from its region's largest part there, or
    // on the first mask where that part is no tool's tip entering once.
    void measure_single(const GestureSegmenterParams& p, std::span<GestureBlob> blobs);
    // The one-tool mask and its regions (single_binary, single_labels, single_ops) in
    // the box [x0, x1] x [y0, y1] of the first mask's pixels: as over the whole picture
    // for every region of it inside one of the first mask's regions there.
    void single_mask_in_box(const GestureSegmenterParams& p, int x0, int y0, int x1, int y1);
};

namespace {

// A second mask for one tool (GestureSegmenterParams::single_threshold).
bool single_mask(const GestureSegmenterParams& p) {
    return p.method == GestureSegmentation::kLikelihood && p.single_threshold > p.threshold;
}

// The region's arms leaving the tip window: runs of region pixels on the circle of
// radius `r` about (cx, cy) in `win` (window pixels; outside it counts as empty).
// A tool's end: one (its shaft); two crossing tools' jaws: two (the two shafts); a
// point along a shaft: two, opposite, or more where another tool passes. 0 when the
// circle misses the region (the window holds all of it) or lies wholly inside it.
int count_arms(const cv::Mat& win, double cx, double cy, double r) {
    const int n = std::clamp(static_cast<int>(2 * M_PI * r), 16, 720);
    auto set = [&](int i) {
        const double a = 2 * M_PI * i / n;
        const int x = static_cast<int>(std::lround(cx + r * std::cos(a)));
        const int y = static_cast<int>(std::lround(cy + r * std::sin(a)));
        return x >= 0 && y >= 0 && x < win.cols && y < win.rows && win.at<std::uint8_t>(y, x) != 0;
    };
    int start = -1;
    for (int i = 0; i < n && start < 0; ++i)
        if (!set(i)) start = i;
    if (start < 0) return 0;  // all set: no end here
    int arms = 0, run = 0;
    for (int k = 1; k <= n; ++k) {
        if (set((start + k) % n)) {
            ++run;
        } else {
            if (run >= 2) ++arms;
            run = 0;
        }
    }
    return arms;
}

// The mean of B, G and R, truncated, for one row of `width` pixels.
ENDOTOWER_WIDE_VECTORS void grey_row(const std::uint8_t* bgr, std::uint8_t* grey, int width) {
    for (int x = 0; x < width; ++x, bgr += 3)
        grey[x] = static_cast<std::uint8_t>((bgr[0] + bgr[1] + bgr[2]) / 3);
}

// 255 where `p` is at least `t` and `lit` is set, else 0, for one row of `width` pixels.
ENDOTOWER_WIDE_VECTORS void at_least_lit(const std::uint8_t* p, const std::uint8_t* lit,
                                         std::uint8_t t, std::uint8_t* out, int width) {
    for (int x = 0; x < width; ++x)
        out[x] = static_cast<std::uint8_t>((p[x] >= t ? 255 : 0) & (lit[x] != 0 ? 255 : 0));
}

// `p` where `lit` is set, else 0, for one row of `width` pixels.
ENDOTOWER_WIDE_VECTORS void keep_lit(const std::uint8_t* lit, std::uint8_t* p, int width) {
    for (int x = 0; x < width; ++x) p[x] = lit[x] != 0 ? p[x] : 0;
}

}  // namespace

void GestureSegmenter::Work::run_band(Band& b) {
    if (band_reduce) {
        const std::size_t first = static_cast<std::size_t>(b.y0) * b.reduce.factor();
        b.reduce.run(frame->data + first * frame->format.stride, frame->format.stride,
                     small.ptr(b.y0), small.step);
    }
    const int W = small.cols;
    // The histogram four in turn: runs of one grey value do not wait on one counter.
    for (auto& h : b.hists) h.fill(0);
    for (int y = b.y0; y < b.y1; ++y) {
        const std::uint8_t* bgr = small.ptr<std::uint8_t>(y);
        std::uint8_t* g = gray.ptr<std::uint8_t>(y);
        grey_row(bgr, g, W);
        int x = 0;
        for (; x + 4 <= W; x += 4)
            for (int j = 0; j < 4; ++j) ++b.hists[j][g[x + j]];
        for (; x < W; ++x) ++b.hists[0][g[x]];
        if (table == nullptr) continue;
        // The cells a row at a time, vectorised; the table lookups one by one.
        ToolLikelihood::cells(bgr, b.cells.data(), W);
        std::uint8_t* q = blurred.ptr<std::uint8_t>(y);
        for (x = 0; x < W; ++x) q[x] = table[b.cells[x]];
    }
}

void GestureSegmenter::Work::measure_regions(RegionScratch& s) {
    while (found_count.load(std::memory_order_acquire) < static_cast<int>(kMaxBlobs)) {
        const std::size_t i = next_region.fetch_add(1, std::memory_order_relaxed);
        if (i >= regions.size()) return;
        s.label = regions[i].label;
        if (!measure_region(s)) continue;
        const auto slot =
            static_cast<std::size_t>(found_slots.fetch_add(1, std::memory_order_relaxed));
        if (slot < found.size()) found[slot] = {i, s.blob};  // always (the bound above)
        found_count.fetch_add(1, std::memory_order_release);
    }
}

void GestureSegmenter::Work::share(Part p) {
    part = p;
    if (band_count == 2)
        helper->post(
            [](void* work) {
                auto& w = *static_cast<Work*>(work);
                w.part(w, 1);
            },
            this);
    p(*this, 0);
    if (band_count == 2) helper->wait();
}

bool GestureSegmenter::Work::measure_region(RegionScratch& s) {
    const GestureSegmenterParams& p = *params;
    const int W = small.cols, H = small.rows;
    const double fcx = field.cx, fcy = field.cy, fr = field.r, touch = field.touch;
    // Nearer the rim than `touch` (the field of view's circle or the picture's edge).
    // The square root only near the circle: well inside it, r >= touch + 1 for sure.
    const double inner = std::max(0.0, fr - touch - 1.0), inner2 = inner * inner;
    auto entering = [&](int x, int y) {
        if (std::min<double>({x + 1.0, y + 1.0, double(W - x), double(H - y)}) < touch) return true;
        const double dx = x - fcx, dy = y - fcy;
        if (dx * dx + dy * dy < inner2) return false;
        return fr - std::hypot(dx, dy) < touch;
    };
    const Component& c = mask_ops->components()[s.label];
    const cv::Mat& binary = *mask_binary;
    const cv::Mat& labels = *mask_labels;
    const int bx = c.left, by = c.top, bw = c.right - c.left + 1, bh = c.bottom - c.top + 1;
    // The distance transform in the box and one pixel around (the whole region's
    // nearest zeros lie there: exactly cv::distanceTransform's values).
    const int dx0 = std::max(0, bx - 1), dy0 = std::max(0, by - 1);
    const int dx1 = std::min(W, bx + bw + 1), dy1 = std::min(H, by + bh + 1);
    s.distances.chamfer(BytePlane{binary.data, W, H, binary.step}, dx0, dy0, dx1, dy1,
                        s.dist.data());
    s.pixels.clear();
    s.entries.clear();
    std::uint32_t radius_fixed = 0;
    for (int y = by; y < by + bh; ++y) {
        const int* l = labels.ptr<int>(y);
        const std::uint32_t* d =
            s.dist.data() + static_cast<std::size_t>(y - dy0) * (dx1 - dx0) - dx0;
        for (int x = bx; x < bx + bw; ++x) {
            if (l[x] != s.label) continue;
            s.pixels.push_back({x, y});
            if (entering(x, y))
                s.entries.push_back({x, y}), radius_fixed = std::max(radius_fixed, d[x]);
        }
    }
    // As cv::distanceTransform: float(distance) x 2^-16.
    float radius = static_cast<float>(radius_fixed) * (1.0f / 65536.0f);
    if (s.entries.empty()) return false;  // not entering from outside: not a tool
    {  // A tool is a shaft: long for its width (second moments of the region).
        double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
        for (const auto& p : s.pixels) mx += p.x, my += p.y;
        mx /= s.pixels.size(), my /= s.pixels.size();
        for (const auto& p : s.pixels)
            sxx += (p.x - mx) * (p.x - mx), syy += (p.y - my) * (p.y - my),
                sxy += (p.x - mx) * (p.y - my);
        const double tr = sxx + syy, det = sxx * syy - sxy * sxy,
                     disc = std::sqrt(std::max(0.0, tr * tr / 4 - det));
        const double l1 = tr / 2 + disc, l2 = std::max(1e-9, tr / 2 - disc);
        if (l1 < p.min_elongation * p.min_elongation * l2) return false;
    }
    // One or two entries: the entry pixels' two extremes, split if far apart.
    auto d2 = [](const Work::Px& a, const Work::Px& b) {
        return double(a.x - b.x) * (a.x - b.x) + double(a.y - b.y) * (a.y - b.y);
    };
    Work::Px pa = s.entries[0], pb = pa;
    for (const auto& e : s.entries)
        if (d2(e, s.entries[0]) > d2(pa, s.entries[0])) pa = e;
    for (const auto& e : s.entries)
        if (d2(e, pa) > d2(pb, pa)) pb = e;
    const bool two = std::sqrt(d2(pa, pb)) > 6.0 * std::max(2.0f, radius);
    double ax = 0, ay = 0, bx2 = 0, by2 = 0;
    int na = 0, nb = 0;
    std::uint32_t ra_fixed = 0, rb_fixed = 0;  // each entry's shaft radius
    // With two: how near each comes to the rim, its farthest pixel from the field
    // of view's centre (squared) and its nearest to the picture's edge.
    double qa = 0, qb = 0, edge_a = W + H, edge_b = W + H;
    for (const auto& e : s.entries) {
        const std::uint32_t d =
            s.dist[static_cast<std::size_t>(e.y - dy0) * (dx1 - dx0) + (e.x - dx0)];
        if (!two) {
            ax += e.x, ay += e.y, ++na, ra_fixed = std::max(ra_fixed, d);
            continue;
        }
        const double q = (e.x - fcx) * (e.x - fcx) + (e.y - fcy) * (e.y - fcy),
                     edge = std::min({e.x + 1.0, e.y + 1.0, double(W - e.x), double(H - e.y)});
        if (d2(e, pb) < d2(e, pa)) {
            bx2 += e.x, by2 += e.y, ++nb, rb_fixed = std::max(rb_fixed, d);
            qb = std::max(qb, q), edge_b = std::min(edge_b, edge);
        } else {
            ax += e.x, ay += e.y, ++na, ra_fixed = std::max(ra_fixed, d);
            qa = std::max(qa, q), edge_a = std::min(edge_a, edge);
        }
    }
    // A shaft crosses the rim; a jaw's end that only comes near it (an open jaw
    // reaching towards the rim) is no entry: where one of the two does not reach
    // within `entry_rim_fraction` x width of the rim, the region enters once.
    if (nb > 0 && p.entry_rim_fraction > 0) {
        const double crossing = p.entry_rim_fraction * W;
        const bool a_in = std::min(fr - std::sqrt(qa), edge_a) <= crossing,
                   b_in = std::min(fr - std::sqrt(qb), edge_b) <= crossing;
        if (a_in != b_in) {
            if (b_in) ax = bx2, ay = by2, na = nb, ra_fixed = rb_fixed;
            nb = 0, bx2 = by2 = 0;
            radius = static_cast<float>(ra_fixed) * (1.0f / 65536.0f);
        }
    }
    ax /= na, ay /= na;
    if (nb > 0) bx2 /= nb, by2 /= nb;
    auto reach = [&](const Work::Px& p) {
        const double da = std::hypot(p.x - ax, p.y - ay);
        return nb > 0 ? std::min(da, std::hypot(p.x - bx2, p.y - by2)) : da;
    };
    // sqrt(dx^2 + dy^2) is within a few ulp of hypot: hypot only where that could
    // change the farthest reach or the 97 % cut.
    auto approx = [&](const Work::Px& p) {
        const double dx = p.x - ax, dy = p.y - ay, ex = p.x - bx2, ey = p.y - by2;
        const double q = dx * dx + dy * dy;
        return std::sqrt(nb > 0 ? std::min(q, ex * ex + ey * ey) : q);
    };
    constexpr double kSlack = 1e-12;
    double far_approx = -1;
    for (std::size_t i = 0; i < s.pixels.size(); ++i)
        far_approx = std::max(far_approx, s.reach[i] = approx(s.pixels[i]));
    double far = -1;
    for (std::size_t i = 0; i < s.pixels.size(); ++i)
        if (s.reach[i] >= far_approx * (1 - kSlack)) far = std::max(far, reach(s.pixels[i]));
    // The tip: mean of the pixels within 3 % of the farthest reach.
    const double cut = 0.97 * far;
    double tx = 0, ty = 0;
    int nt = 0;
    for (std::size_t i = 0; i < s.pixels.size(); ++i) {
        const double r = s.reach[i];
        if (r > cut * (1 + kSlack) || (r >= cut * (1 - kSlack) && reach(s.pixels[i]) >= cut))
            tx += s.pixels[i].x, ty += s.pixels[i].y, ++nt;
    }
    tx /= nt, ty /= nt;
    if (radius < 1.0f) radius = 1.0f;
    const double R = p.window_radii * radius;
    const int x0 = std::max(0, static_cast<int>(tx - R) - 1),
              y0 = std::max(0, static_cast<int>(ty - R) - 1);
    const int x1 = std::min(W, static_cast<int>(tx + R) + 2),
              y1 = std::min(H, static_cast<int>(ty + R) + 2);
    cv::Mat win = s.window(cv::Rect(x0, y0, x1 - x0, y1 - y0));
    win.setTo(0);
    // hypot(dx, dy) <= R, the square root only where dx^2 + dy^2 is within 1e-9 of R^2.
    const double r2_in = R * R * (1 - 1e-9), r2_out = R * R * (1 + 1e-9);
    for (const auto& p : s.pixels) {
        if (p.x < x0 || p.x >= x1 || p.y < y0 || p.y >= y1) continue;
        const double dx = p.x - tx, dy = p.y - ty, q = dx * dx + dy * dy;
        if (q <= r2_in || (q < r2_out && std::hypot(dx, dy) <= R))
            win.at<std::uint8_t>(p.y - y0, p.x - x0) = 255;
    }
    GestureBlob& b = s.blob;
    if (defer_one_tool && nb == 0) {
        // One tool with two masks: measured in full once, by measure_single(); here only
        // whether it is a tool's tip, as the features' `valid` would say.
        b = GestureBlob{};
        b.entries = 1;
        return gesture_features_valid(win.data, win.cols, win.rows, static_cast<int>(win.step),
                                      s.tracer);
    }
    b.arms = count_arms(win, tx - x0, ty - y0, R - 1.5);  // before the tracer marks it
    // Two tools, one much thicker near the scope: the window of the thinner shaft.
    b.thin_arms = 0;
    if (nb > 0) {
        const double r_thin =
            std::max(1.0, static_cast<double>(std::min(ra_fixed, rb_fixed)) * (1.0 / 65536.0));
        b.thin_arms = count_arms(win, tx - x0, ty - y0, p.window_radii * r_thin - 1.5);
    }
    // The profile's axis: from the tip to the entry it was reached from.
    GestureFeatures profile;
    if (p.profile) {
        double ex = ax, ey = ay;
        if (nb > 0 && std::hypot(tx - bx2, ty - by2) < std::hypot(tx - ax, ty - ay))
            ex = bx2, ey = by2;
        const double len = std::max(1e-9, std::hypot(ex - tx, ey - ty));
        measure_tip_profile(win.data, win.cols, win.rows, static_cast<int>(win.step), tx - x0,
                            ty - y0, (ex - tx) / len, (ey - ty) / len, radius, profile);
    }
    b.features = measure_gesture_features(win.data, win.cols, win.rows, static_cast<int>(win.step),
                                          s.tracer);
    b.features.profile_width = profile.profile_width;
    b.features.profile_runs = profile.profile_runs;
    if (!b.features.valid) return false;
    b.tip = {tx / scale, ty / scale};
    b.radius_px = radius / scale;
    b.entries = nb > 0 ? 2 : 1;
    return true;
}

GestureSegmenter::GestureSegmenter(const ToolLikelihood* model, GestureSegmenterParams params)
    : model_(model), params_(params), work_(std::make_unique<Work>()) {}
GestureSegmenter::~GestureSegmenter() = default;

void GestureSegmenter::configure(const hal::FrameFormat& format) {
    Work& w = *work_;
    w.scale = std::min(1.0, static_cast<double>(params_.analysis_width) / format.width);
    const int sw = std::max(1, static_cast<int>(std::lround(format.width * w.scale)));
    const int sh = std::max(1, static_cast<int>(std::lround(format.height * w.scale)));
    w.small.create(sh, sw, CV_8UC3);
    w.reduce.configure(format.width, format.height, sw, sh, 3);
    for (cv::Mat* m : {&w.gray, &w.blurred, &w.lit, &w.eroded, &w.a, &w.opened, &w.binary})
        m->create(sh, sw, CV_8U);
    w.labels.create(sh, sw, CV_32S);
    w.ops.configure(sw, sh);
    if (single_mask(params_)) {
        for (cv::Mat* m : {&w.smoothed, &w.single_binary}) m->create(sh, sw, CV_8U);
        w.single_labels.create(sh, sw, CV_32S);
        w.single_ops.configure(sw, sh);
    }
    // Two bands of rows (halves) with `threads` = 2, else one; each band's own block
    // mean where the reduction is one (integer factor k: band rows [y0, y1) are the
    // input rows [k y0, k y1)).
    w.band_count = params_.threads >= 2 && sh >= 2 ? 2 : 1;
    if (w.band_count == 2 && !w.helper) {
        try {
            w.helper = std::make_unique<app::HelperThread>();
        } catch (const std::system_error&) {
            w.band_count = 1;  // no thread to be had (a process limit): all on the caller
        }
    }
    const int k = format.width / sw;
    const bool block = format.width == k * sw && format.height == k * sh;
    for (int i = 0; i < 2; ++i) {
        Work::Band& b = w.bands[i];
        b.y0 = i == 0 ? 0 : (w.band_count == 2 ? sh / 2 : sh);
        b.y1 = i == 0 && w.band_count == 2 ? sh / 2 : sh;
        b.reduce = BlockMean{};
        if (block && b.y1 > b.y0)
            b.reduce.configure(format.width, k * (b.y1 - b.y0), sw, b.y1 - b.y0, 3);
        b.cells.assign(static_cast<std::size_t>(sw), 0);
    }
    const int big =
        std::max(3, static_cast<int>(std::lround(params_.large_element_fraction * sw)) | 1);
    w.large_element = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(big, big));
    const int s = std::max(1, params_.small_element);
    w.small_element = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(s, s));
    MaskOps::ellipse_rows(3, w.fov_rows);  // 7x7
    // Every list at its largest possible size: no reallocation per frame, whatever the mask.
    const auto area = static_cast<std::size_t>(sw) * sh;
    for (int i = 0; i < w.band_count; ++i) {  // the second only for the helper
        Work::RegionScratch& rs = w.scratch[i];
        rs.distances.configure_chamfer(sw, sh);
        rs.tracer.reserve(sw, sh);
        rs.dist.resize(area);
        rs.reach.resize(area);
        rs.pixels.reserve(area);
        rs.entries.reserve(area);
        rs.window.create(sh, sw, CV_8U);
    }
    w.regions.reserve(static_cast<std::size_t>((sw + 1) / 2) * ((sh + 1) / 2) + 1);
}

std::size_t GestureSegmenter::segment(const hal::Frame& frame,
                                      std::span<GestureBlob, kMaxBlobs> out) {
    Work& w = *work_;
    if (frame.format.pixel_format != hal::PixelFormat::kBgr24 || w.small.empty()) return 0;
    if (params_.method == GestureSegmentation::kLikelihood &&
        (model_ == nullptr || !model_->trained()))
        return 0;
    const int W = w.small.cols, H = w.small.rows;
    // The reduction in the bands where it is their block mean (the frame of the size
    // configured), else here first.
    w.band_reduce =
        w.bands[0].reduce.ready() && w.reduce.fits(frame.format.width, frame.format.height);
    if (!w.band_reduce) detail::reduce_frame(frame, w.reduce, w.small);
    w.frame = &frame;
    w.table = params_.method == GestureSegmentation::kLikelihood ? model_->table().data() : nullptr;
    w.share([](Work& ww, int i) { ww.run_band(ww.bands[static_cast<std::size_t>(i)]); });
    std::array<int, 256> hist{};
    for (int i = 0; i < w.band_count; ++i)
        for (const auto& h : w.bands[i].hists)
            for (int v = 0; v < 256; ++v) hist[v] += h[v];
    // The lit field of view (as LikelihoodToolTracker): brighter than 0.35 x the median
    // after a 9x9 mean, so a dark shaft inside it stays inside; then eroded (7x7 ellipse).
    int median = 0;
    for (int acc = 0; median < 255 && (acc += hist[median]) < W * H / 2;) ++median;
    auto plane = [](cv::Mat& m) {
        return BytePlane{m.data, m.cols, m.rows, static_cast<std::size_t>(m.step)};
    };
    // cv::threshold compares 8-bit pixels with the threshold's floor.
    const int lit_threshold = static_cast<int>(std::floor(std::max(12.0, 0.35 * median)));
    const LitMoments fov = w.ops.lit_field(plane(w.gray), lit_threshold, plane(w.lit));
    if (fov.m00 <= 0) return 0;
    const double fcx = fov.m10 / fov.m00, fcy = fov.m01 / fov.m00, fr = std::sqrt(fov.m00 / M_PI);
    w.ops.morph(plane(w.lit), plane(w.eroded), std::span<const int>(w.fov_rows.data(), 7), true);

    if (params_.method == GestureSegmentation::kLikelihood) {
        // The tool probability (the bands'), only where lit: the 5x5 Gaussian of a
        // pixel inside the eroded field of view reads only lit pixels (the ellipse
        // covers its 5x5), and every other pixel is cleared by the AND below, so the
        // mask is the same.
        for (int y = 0; y < H; ++y)
            keep_lit(w.lit.ptr<std::uint8_t>(y), w.blurred.ptr<std::uint8_t>(y), W);
        w.ops.smooth_at_least(plane(w.blurred), params_.threshold, plane(w.eroded), plane(w.binary),
                              single_mask(params_) ? plane(w.smoothed) : BytePlane{});
        w.ops.open3(plane(w.binary), plane(w.binary));
    } else {
        // eq. 3.3: A - (A o B1); eq. 3.5: A + (A o B2); then a high threshold.
        cv::bitwise_not(w.gray, w.a);
        cv::bitwise_and(w.a, w.eroded, w.a);
        cv::morphologyEx(w.a, w.opened, cv::MORPH_OPEN, w.large_element);
        cv::subtract(w.a, w.opened, w.a);
        cv::morphologyEx(w.a, w.opened, cv::MORPH_OPEN, w.small_element);
        cv::add(w.a, w.opened, w.a);
        cv::threshold(w.a, w.binary, params_.high_threshold - 1, 255, cv::THRESH_BINARY);
    }
    const int n = w.ops.label(plane(w.binary), w.labels.ptr<std::int32_t>(0));
    const std::vector<Component>& comps = w.ops.components();
    const double min_area = params_.min_area_fraction * W * H,
                 touch = params_.border_touch_fraction * W;
    w.regions.clear();
    for (int i = 1; i < n; ++i)
        if (comps[i].area >= min_area) w.regions.push_back({i, comps[i].area});
    // Largest first; equal areas by label (first pixel in raster order).
    std::sort(w.regions.begin(), w.regions.end(), [](const Work::Region& a, const Work::Region& b) {
        return a.area != b.area ? a.area > b.area : a.label < b.label;
    });
    if (w.regions.empty()) return 0;
    // Each region's tip and features until kMaxBlobs are found, the regions taken in size
    // order by whichever thread is free (the caller, the helper); the blobs are the first
    // kMaxBlobs found in size order, as one thread finds them. A thread stops taking
    // regions once kMaxBlobs are found, and every region it took before is smaller in
    // the order than any it did not take, so those first kMaxBlobs are among the found.
    w.field = {fcx, fcy, fr, touch};
    w.params = &params_;
    w.defer_one_tool = single_mask(params_);
    const std::size_t found = std::min(w.measure_found(w.ops, w.binary, w.labels), out.size());
    w.defer_one_tool = false;
    for (std::size_t i = 0; i < found; ++i) out[i] = w.found[i].blob;
    if (single_mask(params_)) w.measure_single(params_, out.first(found));
    return found;
}

std::size_t GestureSegmenter::Work::measure_found(const MaskOps& o, const cv::Mat& b,
                                                  const cv::Mat& l) {
    mask_ops = &o, mask_binary = &b, mask_labels = &l;
    next_region.store(0, std::memory_order_relaxed);
    found_count.store(0, std::memory_order_relaxed);
    found_slots.store(0, std::memory_order_relaxed);
    share([](Work& ww, int i) { ww.measure_regions(ww.scratch[static_cast<std::size_t>(i)]); });
    const auto n = std::min(found.size(),
                            static_cast<std::size_t>(found_slots.load(std::memory_order_relaxed)));
    std::sort(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(n),
              [](const Found& a, const Found& b) { return a.region < b.region; });
    return n;
}

void GestureSegmenter::Work::measure_single(const GestureSegmenterParams& p,
                                            std::span<GestureBlob> blobs) {
    // Each one-entry blob's region (its label in `labels`), before `regions` is reused.
    std::array<int, kMaxBlobs> owner{};
    for (std::size_t i = 0; i < blobs.size(); ++i)
        owner[i] = blobs[i].entries == 1 ? regions[found[i].region].label : 0;
    const int W = small.cols, H = small.rows;
    // The second mask only in the box of those regions.
    int x0 = W, y0 = H, x1 = -1, y1 = -1;
    for (std::size_t i = 0; i < blobs.size(); ++i) {
        if (owner[i] == 0) continue;
        const Component& c = ops.components()[owner[i]];
        x0 = std::min(x0, c.left), y0 = std::min(y0, c.top);
        x1 = std::max(x1, c.right), y1 = std::max(y1, c.bottom);
    }
    if (x1 < 0) return;
    single_mask_in_box(p, x0, y0, x1, y1);
    const std::vector<Component>& comps = single_ops.components();
    const double min_area = p.min_area_fraction * W * H;
    // Per blob, the largest region of the one-tool mask inside its region (the one-tool
    // mask lies inside the other: a higher threshold, the same opening).
    regions.clear();
    std::array<int, kMaxBlobs> candidate{};
    for (std::size_t i = 0; i < blobs.size(); ++i) {
        if (owner[i] == 0) continue;
        const Component& c = ops.components()[owner[i]];
        int best = 0;
        for (int y = c.top; y <= c.bottom; ++y) {
            const std::int32_t* l = labels.ptr<std::int32_t>(y);
            const std::int32_t* sl = single_labels.ptr<std::int32_t>(y);
            for (int x = c.left; x <= c.right; ++x) {
                const int k = sl[x];
                if (k == 0 || k == best || l[x] != owner[i] || comps[k].area < min_area) continue;
                if (best == 0 || comps[k].area > comps[best].area ||
                    (comps[k].area == comps[best].area && k < best))
                    best = k;
            }
        }
        if (best == 0) continue;
        candidate[regions.size()] = static_cast<int>(i);
        regions.push_back({best, comps[best].area});
    }
    // Measured in full: on the second mask, or where that has no tool's tip entering
    // once inside the region, on the first, as with one mask.
    std::array<bool, kMaxBlobs> done{};
    if (!regions.empty()) {
        const std::size_t n = measure_found(single_ops, single_binary, single_labels);
        for (std::size_t j = 0; j < n; ++j) {
            const auto i = static_cast<std::size_t>(candidate[found[j].region]);
            if (found[j].blob.entries == 1) blobs[i] = found[j].blob, done[i] = true;
        }
    }
    regions.clear();
    for (std::size_t i = 0; i < blobs.size(); ++i)
        if (owner[i] != 0 && !done[i]) {
            candidate[regions.size()] = static_cast<int>(i);
            regions.push_back({owner[i], ops.components()[owner[i]].area});
        }
    if (regions.empty()) return;
    // Found before (its window holds a blob), so found again.
    const std::size_t n = measure_found(ops, binary, labels);
    for (std::size_t j = 0; j < n; ++j)
        blobs[static_cast<std::size_t>(candidate[found[j].region])] = found[j].blob;
}

void GestureSegmenter::Work::single_mask_in_box(const GestureSegmenterParams& p, int x0, int y0,
                                                int x1, int y1) {
    // The box and 2 px around (what the opening reads): each region of the second mask
    // that lies in one of the first's in the box lies in the box, and is the same there
    // as over the whole picture once the ring the opening could not see whole is
    // cleared (measure_region reads only inside a region's box and 1 px around).
    const int W = small.cols, H = small.rows;
    constexpr int kRing = 2;
    const int bx0 = std::max(0, x0 - kRing), by0 = std::max(0, y0 - kRing);
    const int bx1 = std::min(W - 1, x1 + kRing), by1 = std::min(H - 1, y1 + kRing);
    const auto at_least = static_cast<std::uint8_t>(p.single_threshold);
    for (int y = by0; y <= by1; ++y)
        at_least_lit(smoothed.ptr<std::uint8_t>(y) + bx0, eroded.ptr<std::uint8_t>(y) + bx0,
                     at_least, single_binary.ptr<std::uint8_t>(y) + bx0, bx1 - bx0 + 1);
    const BytePlane plane{single_binary.ptr<std::uint8_t>(by0) + bx0, bx1 - bx0 + 1, by1 - by0 + 1,
                          static_cast<std::size_t>(single_binary.step)};
    single_ops.open3(plane, plane);
    // The ring inside the picture: the opening there saw only part of its 5x5.
    for (int y = by0; y <= by1; ++y) {
        std::uint8_t* o = single_binary.ptr<std::uint8_t>(y);
        const bool ring_row = (y < y0 && by0 > 0) || (y > y1 && by1 < H - 1);
        for (int x = bx0; x <= bx1; ++x)
            if (ring_row || (x < x0 && bx0 > 0) || (x > x1 && bx1 < W - 1)) o[x] = 0;
    }
    single_ops.label(plane, single_labels.ptr<std::int32_t>(by0) + bx0, static_cast<std::size_t>(W),
                     bx0, by0);
}

std::span<const std::uint8_t> GestureSegmenter::mask() const {
    const cv::Mat& m = work_->binary;
    return {m.data, m.total()};
}
int GestureSegmenter::mask_width() const {
    return work_->binary.cols;
}

}  // namespace endotower::vision
