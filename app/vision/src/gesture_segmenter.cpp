#include "endotower/vision/gesture_segmenter.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "endotower/vision/block_mean.hpp"

namespace endotower::vision {

struct GestureSegmenter::Work {
    double scale = 1.0;
    BlockMean reduce;  // the odd integer factors (1920 -> 640); others: cv::resize
    cv::Mat small, gray, blurred, lit, a, opened, binary, labels, stats, centroids, dist, window;
    cv::Mat large_element, small_element, open3, fov_element;
    struct Px {
        int x, y;
    };
    std::vector<Px> pixels, entries;
    struct Region {
        int label, area;
    };
    std::vector<Region> regions;
};

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
    for (cv::Mat* m : {&w.gray, &w.blurred, &w.lit, &w.a, &w.opened, &w.binary, &w.window})
        m->create(sh, sw, CV_8U);
    w.labels.create(sh, sw, CV_32S);
    w.dist.create(sh, sw, CV_32F);
    const int big =
        std::max(3, static_cast<int>(std::lround(params_.large_element_fraction * sw)) | 1);
    w.large_element = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(big, big));
    const int s = std::max(1, params_.small_element);
    w.small_element = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(s, s));
    w.open3 = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
    w.fov_element = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7));
    w.pixels.reserve(static_cast<std::size_t>(sw) * sh);
    w.entries.reserve(static_cast<std::size_t>(sw) * sh / 4);
    w.regions.reserve(256);
}

std::size_t GestureSegmenter::segment(const hal::Frame& frame,
                                      std::span<GestureBlob, kMaxBlobs> out) {
    Work& w = *work_;
    if (frame.format.pixel_format != hal::PixelFormat::kBgr24 || w.small.empty()) return 0;
    if (params_.method == GestureSegmentation::kLikelihood &&
        (model_ == nullptr || !model_->trained()))
        return 0;
    const cv::Mat full(frame.format.height, frame.format.width, CV_8UC3, frame.data,
                       frame.format.stride);
    if (w.reduce.ready())
        w.reduce.run(frame.data, frame.format.stride, w.small.data, w.small.step);
    else if (w.scale < 1.0)
        cv::resize(full, w.small, w.small.size(), 0, 0, cv::INTER_AREA);
    else
        full.copyTo(w.small);
    const int W = w.small.cols, H = w.small.rows;

    // Luma (and the tool probability) per pixel; brightness histogram for the field of view.
    // Four histograms in turn: runs of one grey value do not wait on one counter.
    std::array<std::array<int, 256>, 4> hists{};
    const bool like = params_.method == GestureSegmentation::kLikelihood;
    const std::uint8_t* table = like ? model_->table().data() : nullptr;
    for (int y = 0; y < H; ++y) {
        const std::uint8_t* p = w.small.ptr<std::uint8_t>(y);
        std::uint8_t* g = w.gray.ptr<std::uint8_t>(y);
        int x = 0;
        for (; x + 4 <= W; x += 4, p += 12)
            for (int j = 0; j < 4; ++j) {
                const auto v =
                    static_cast<std::uint8_t>((p[3 * j] + p[3 * j + 1] + p[3 * j + 2]) / 3);
                g[x + j] = v;
                ++hists[j][v];
            }
        for (; x < W; ++x, p += 3) {
            g[x] = static_cast<std::uint8_t>((p[0] + p[1] + p[2]) / 3);
            ++hists[0][g[x]];
        }
        if (table == nullptr) continue;
        p = w.small.ptr<std::uint8_t>(y);
        std::uint8_t* q = w.binary.ptr<std::uint8_t>(y);
        for (x = 0; x < W; ++x, p += 3) q[x] = table[ToolLikelihood::cell(p[0], p[1], p[2])];
    }
    std::array<int, 256> hist{};
    for (int v = 0; v < 256; ++v) hist[v] = hists[0][v] + hists[1][v] + hists[2][v] + hists[3][v];
    // The lit field of view (as LikelihoodToolTracker): brighter than 0.35 x the median
    // after a 9x9 mean, so a dark shaft inside it stays inside.
    int median = 0;
    for (int acc = 0; median < 255 && (acc += hist[median]) < W * H / 2;) ++median;
    cv::blur(w.gray, w.blurred, cv::Size(9, 9));
    cv::threshold(w.blurred, w.lit, std::max(12.0, 0.35 * median), 255, cv::THRESH_BINARY);
    const cv::Moments fov = cv::moments(w.lit, true);
    if (fov.m00 <= 0) return 0;
    const double fcx = fov.m10 / fov.m00, fcy = fov.m01 / fov.m00, fr = std::sqrt(fov.m00 / M_PI);
    cv::erode(w.lit, w.lit, w.fov_element);

    if (params_.method == GestureSegmentation::kLikelihood) {
        cv::GaussianBlur(w.binary, w.binary, cv::Size(5, 5), 1.2);
        cv::threshold(w.binary, w.binary, params_.threshold - 1, 255, cv::THRESH_BINARY);
        cv::bitwise_and(w.binary, w.lit, w.binary);
        cv::morphologyEx(w.binary, w.binary, cv::MORPH_OPEN, w.open3);
    } else {
        // eq. 3.3: A - (A o B1); eq. 3.5: A + (A o B2); then a high threshold.
        cv::bitwise_not(w.gray, w.a);
        cv::bitwise_and(w.a, w.lit, w.a);
        cv::morphologyEx(w.a, w.opened, cv::MORPH_OPEN, w.large_element);
        cv::subtract(w.a, w.opened, w.a);
        cv::morphologyEx(w.a, w.opened, cv::MORPH_OPEN, w.small_element);
        cv::add(w.a, w.opened, w.a);
        cv::threshold(w.a, w.binary, params_.high_threshold - 1, 255, cv::THRESH_BINARY);
    }
    const int n =
        cv::connectedComponentsWithStats(w.binary, w.labels, w.stats, w.centroids, 8, CV_32S);
    const double min_area = params_.min_area_fraction * W * H,
                 touch = params_.border_touch_fraction * W;
    w.regions.clear();
    for (int i = 1; i < n; ++i)
        if (w.stats.at<int>(i, cv::CC_STAT_AREA) >= min_area)
            w.regions.push_back({i, w.stats.at<int>(i, cv::CC_STAT_AREA)});
    std::sort(w.regions.begin(), w.regions.end(),
              [](const Work::Region& a, const Work::Region& b) { return a.area > b.area; });
    if (w.regions.empty()) return 0;
    cv::distanceTransform(w.binary, w.dist, cv::DIST_L2, 3);
    auto rim_distance = [&](int x, int y) {
        const double r = fr - std::hypot(x - fcx, y - fcy);
        return std::min<double>({r, x + 1.0, y + 1.0, double(W - x), double(H - y)});
    };

    std::size_t found = 0;
    for (const Work::Region& reg : w.regions) {
        if (found == out.size()) break;
        const int bx = w.stats.at<int>(reg.label, cv::CC_STAT_LEFT),
                  by = w.stats.at<int>(reg.label, cv::CC_STAT_TOP);
        const int bw = w.stats.at<int>(reg.label, cv::CC_STAT_WIDTH),
                  bh = w.stats.at<int>(reg.label, cv::CC_STAT_HEIGHT);
        w.pixels.clear();
        w.entries.clear();
        float radius = 0;
        for (int y = by; y < by + bh; ++y) {
            const int* l = w.labels.ptr<int>(y);
            const float* d = w.dist.ptr<float>(y);
            for (int x = bx; x < bx + bw; ++x) {
                if (l[x] != reg.label) continue;
                w.pixels.push_back({x, y});
                if (rim_distance(x, y) < touch)
                    w.entries.push_back({x, y}), radius = std::max(radius, d[x]);
            }
        }
        if (w.entries.empty()) continue;  // not entering from outside: not a tool
        {  // A tool is a shaft: long for its width (second moments of the region).
            double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
            for (const auto& p : w.pixels) mx += p.x, my += p.y;
            mx /= w.pixels.size(), my /= w.pixels.size();
            for (const auto& p : w.pixels)
                sxx += (p.x - mx) * (p.x - mx), syy += (p.y - my) * (p.y - my),
                    sxy += (p.x - mx) * (p.y - my);
            const double tr = sxx + syy, det = sxx * syy - sxy * sxy,
                         disc = std::sqrt(std::max(0.0, tr * tr / 4 - det));
            const double l1 = tr / 2 + disc, l2 = std::max(1e-9, tr / 2 - disc);
            if (l1 < params_.min_elongation * params_.min_elongation * l2) continue;
        }
        // One or two entries: the entry pixels' two extremes, split if far apart.
        auto d2 = [](const Work::Px& a, const Work::Px& b) {
            return double(a.x - b.x) * (a.x - b.x) + double(a.y - b.y) * (a.y - b.y);
        };
        Work::Px pa = w.entries[0], pb = pa;
        for (const auto& e : w.entries)
            if (d2(e, w.entries[0]) > d2(pa, w.entries[0])) pa = e;
        for (const auto& e : w.entries)
            if (d2(e, pa) > d2(pb, pa)) pb = e;
        const bool two = std::sqrt(d2(pa, pb)) > 6.0 * std::max(2.0f, radius);
        double ax = 0, ay = 0, bx2 = 0, by2 = 0;
        int na = 0, nb = 0;
        for (const auto& e : w.entries) {
            if (two && d2(e, pb) < d2(e, pa))
                bx2 += e.x, by2 += e.y, ++nb;
            else
                ax += e.x, ay += e.y, ++na;
        }
        ax /= na, ay /= na;
        if (nb > 0) bx2 /= nb, by2 /= nb;
        auto reach = [&](const Work::Px& p) {
            const double da = std::hypot(p.x - ax, p.y - ay);
            return nb > 0 ? std::min(da, std::hypot(p.x - bx2, p.y - by2)) : da;
        };
        double far = -1;
        for (const auto& p : w.pixels) far = std::max(far, reach(p));
        // The tip: mean of the pixels within 3 % of the farthest reach.
        double tx = 0, ty = 0;
        int nt = 0;
        for (const auto& p : w.pixels)
            if (reach(p) >= 0.97 * far) tx += p.x, ty += p.y, ++nt;
        tx /= nt, ty /= nt;
        if (radius < 1.0f) radius = 1.0f;
        const double R = params_.window_radii * radius;
        const int x0 = std::max(0, static_cast<int>(tx - R) - 1),
                  y0 = std::max(0, static_cast<int>(ty - R) - 1);
        const int x1 = std::min(W, static_cast<int>(tx + R) + 2),
                  y1 = std::min(H, static_cast<int>(ty + R) + 2);
        cv::Mat win = w.window(cv::Rect(x0, y0, x1 - x0, y1 - y0));
        win.setTo(0);
        for (const auto& p : w.pixels)
            if (p.x >= x0 && p.x < x1 && p.y >= y0 && p.y < y1 &&
                std::hypot(p.x - tx, p.y - ty) <= R)
                win.at<std::uint8_t>(p.y - y0, p.x - x0) = 255;
        GestureBlob& b = out[found];
        b.features =
            measure_gesture_features(win.data, win.cols, win.rows, static_cast<int>(win.step));
        if (!b.features.valid) continue;
        b.tip = {tx / w.scale, ty / w.scale};
        b.radius_px = radius / w.scale;
        b.entries = nb > 0 ? 2 : 1;
        ++found;
    }
    return found;
}

std::span<const std::uint8_t> GestureSegmenter::mask() const {
    const cv::Mat& m = work_->binary;
    return {m.data, m.total()};
}
int GestureSegmenter::mask_width() const {
    return work_->binary.cols;
}

}  // namespace endotower::vision
