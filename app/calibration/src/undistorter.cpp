#include "endotower/calibration/undistorter.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace endotower::calibration {

struct Undistorter::Impl {
    Calibration cal;
    cv::Mat map_xy, map_frac;  // fixed point: source (x, y) and 5-bit fractions (fy << 5 | fx)
    cv::Mat k, d;
    // Runs of corrected pixels whose four source taps lie in the image and whose
    // source is inside the field of view; everything else is black.
    struct Span {
        int y, x0, x1;  // [x0, x1)
    };
    std::vector<Span> spans;
    // Rows [0, split_row) are one half of the work, [split_row, height) the other;
    // spans[0, split_span) lie in the first.
    int split_row = 0;
    std::size_t split_span = 0;

    // The helper thread that remaps the second half (set_threads(2)); started once.
    struct Helper {
        std::mutex mutex;
        std::condition_variable cv;
        std::thread thread;
        const hal::Frame* in = nullptr;
        hal::Frame* out = nullptr;
        int type = 0;
        std::uint64_t posted = 0, done = 0;
        bool quit = false;
    };
    std::unique_ptr<Helper> helper;

    ~Impl() {
        if (!helper) return;
        {
            std::lock_guard lock(helper->mutex);
            helper->quit = true;
        }
        helper->cv.notify_all();
        helper->thread.join();
    }
};

namespace {

// Bilinear sampling with the fixed-point maps (OpenCV's layout: integer source, 5-bit
// fractions), run by run; the gaps between runs are cleared. No allocation, one thread.
#if defined(__SSE2__)
// One pixel per step, both taps of a row in one register: the horizontal blend in 16
// bits with per-fraction weight tables, the vertical one with madd in 32 bits. Same
// arithmetic as the scalar loop, bit for bit. Returns where it stopped: pixels whose
// 8-byte tap loads would read past the frame are left to the scalar loop.
template <int C>
int remap_run_sse2(const Undistorter::Impl&, const hal::Frame& in, const cv::Vec2s* xy,
                   const std::uint16_t* fr, std::uint8_t* row, int x, int x1, int w) {
    struct Tables {
        __m128i wx[32], wy[32];
        Tables() {
            for (int f = 0; f < 32; ++f) {
                const short a = static_cast<short>(32 - f), b = static_cast<short>(f);
                wx[f] = C == 3 ? _mm_setr_epi16(a, a, a, b, b, b, 0, 0)
                               : _mm_setr_epi16(a, a, a, a, b, b, b, b);
                wy[f] =
                    _mm_set1_epi32(static_cast<int>((static_cast<unsigned>(f) << 16) | (32u - f)));
            }
        }
    };
    static const Tables t;
    const std::size_t ss = in.format.stride;
    const std::uint8_t* src = in.data;
    const std::uint8_t* end =
        src + (in.format.height - 1) * ss + static_cast<std::size_t>(C) * in.format.width;
    const __m128i zero = _mm_setzero_si128(), round = _mm_set1_epi32(512);
    for (; x < x1; ++x) {
        const std::uint8_t* p =
            src + static_cast<std::size_t>(xy[x][1]) * ss + static_cast<std::size_t>(xy[x][0]) * C;
        if (p + ss + 8 > end) break;
        const int fx = fr[x] & 31, fy = fr[x] >> 5;
        __m128i top = _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), zero);
        __m128i bot =
            _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + ss)), zero);
        top = _mm_mullo_epi16(top, t.wx[fx]);
        bot = _mm_mullo_epi16(bot, t.wx[fx]);
        top = _mm_add_epi16(top, _mm_srli_si128(top, 2 * C));
        bot = _mm_add_epi16(bot, _mm_srli_si128(bot, 2 * C));
        __m128i v = _mm_madd_epi16(_mm_unpacklo_epi16(top, bot), t.wy[fy]);
        v = _mm_srli_epi32(_mm_add_epi32(v, round), 10);
        v = _mm_packus_epi16(_mm_packs_epi32(v, zero), zero);
        const std::uint32_t px = static_cast<std::uint32_t>(_mm_cvtsi128_si32(v));
        // A 4-byte store is one instruction; its extra byte (C == 3) lands on the next
        // pixel, written later, except at the row's end.
        // NOLINTNEXTLINE(bugprone-branch-clone): the branches are the same only when C == 4
        if (C == 4 || x + 1 < w)
            std::memcpy(row + C * x, &px, 4);
        else
            std::memcpy(row + C * x, &px, C);
    }
    return x;
}
#endif

// Remaps spans[first, last) and clears the other pixels of rows [row0, row1).
template <int C>
void remap_spans(const Undistorter::Impl& m, const hal::Frame& in, hal::Frame& out,
                 std::size_t first, std::size_t last, int row0, int row1) {
    const std::size_t ss = in.format.stride;
    const std::uint8_t* src = in.data;
    int y = -1, x_done = 0;
    std::uint8_t* row = nullptr;
    const int w = out.format.width;
    auto finish_row = [&]() {
        if (row) std::memset(row + C * x_done, 0, static_cast<std::size_t>(C) * (w - x_done));
    };
    int next_row = row0;
    for (std::size_t i = first; i < last; ++i) {
        const auto& sp = m.spans[i];
        if (sp.y != y) {
            finish_row();
            for (; next_row < sp.y; ++next_row)
                std::memset(out.data + next_row * out.format.stride, 0,
                            static_cast<std::size_t>(C) * w);
            y = sp.y;
            next_row = y + 1;
            row = out.data + static_cast<std::size_t>(y) * out.format.stride;
            x_done = 0;
        }
        std::memset(row + C * x_done, 0, static_cast<std::size_t>(C) * (sp.x0 - x_done));
        const cv::Vec2s* xy = m.map_xy.ptr<cv::Vec2s>(y);
        const std::uint16_t* fr = m.map_frac.ptr<std::uint16_t>(y);
        int x = sp.x0;
#if defined(__SSE2__)
        if constexpr (C == 3 || C == 4) x = remap_run_sse2<C>(m, in, xy, fr, row, x, sp.x1, w);
#endif
        for (; x < sp.x1; ++x) {
            const std::uint8_t* p = src + static_cast<std::size_t>(xy[x][1]) * ss +
                                    static_cast<std::size_t>(xy[x][0]) * C;
            const int fx = fr[x] & 31, fy = fr[x] >> 5;
            const int w00 = (32 - fx) * (32 - fy), w01 = fx * (32 - fy), w10 = (32 - fx) * fy,
                      w11 = fx * fy;
            std::uint8_t* o = row + C * x;
            for (int c = 0; c < C; ++c)
                o[c] = static_cast<std::uint8_t>(
                    (p[c] * w00 + p[c + C] * w01 + p[ss + c] * w10 + p[ss + c + C] * w11 + 512) >>
                    10);
        }
        x_done = sp.x1;
    }
    finish_row();
    for (; next_row < row1; ++next_row)
        std::memset(out.data + next_row * out.format.stride, 0, static_cast<std::size_t>(C) * w);
}

void remap_part(const Undistorter::Impl& m, int type, const hal::Frame& in, hal::Frame& out,
                std::size_t first, std::size_t last, int row0, int row1) {
    switch (CV_ELEM_SIZE(type)) {
        case 1:
            remap_spans<1>(m, in, out, first, last, row0, row1);
            break;
        case 3:
            remap_spans<3>(m, in, out, first, last, row0, row1);
            break;
        default:
            remap_spans<4>(m, in, out, first, last, row0, row1);
            break;
    }
}

void helper_loop(Undistorter::Impl& m) {
    Undistorter::Impl::Helper& h = *m.helper;
    std::unique_lock lock(h.mutex);
    for (;;) {
        h.cv.wait(lock, [&] { return h.quit || h.posted != h.done; });
        if (h.quit) return;
        const hal::Frame& in = *h.in;
        hal::Frame& out = *h.out;
        const int type = h.type;
        lock.unlock();
        remap_part(m, type, in, out, m.split_span, m.spans.size(), m.split_row, in.format.height);
        lock.lock();
        h.done = h.posted;
        h.cv.notify_all();
    }
}

}  // namespace

bool Undistorter::set_threads(int threads) {
    if (!impl_ || threads < 1 || threads > 2) return false;
    if ((threads == 2) == static_cast<bool>(impl_->helper)) return true;
    if (threads == 1) {
        {
            std::lock_guard lock(impl_->helper->mutex);
            impl_->helper->quit = true;
        }
        impl_->helper->cv.notify_all();
        impl_->helper->thread.join();
        impl_->helper.reset();
        return true;
    }
    impl_->helper = std::make_unique<Impl::Helper>();
    impl_->helper->thread = std::thread(helper_loop, std::ref(*impl_));
    return true;
}

int Undistorter::threads() const {
    return impl_ && impl_->helper ? 2 : 1;
}

Undistorter::Undistorter() = default;
Undistorter::~Undistorter() = default;
Undistorter::Undistorter(Undistorter&&) noexcept = default;
Undistorter& Undistorter::operator=(Undistorter&&) noexcept = default;

int Undistorter::width() const {
    return impl_ ? impl_->cal.width : 0;
}
int Undistorter::height() const {
    return impl_ ? impl_->cal.height : 0;
}

Point2 Undistorter::source_of(double x, double y) const {
    const Calibration& c = impl_->cal;
    if (c.model == LensModel::kBook) {
        const RadialPolynomial& p = *c.book;
        const double dx = x - p.cx, dy = y - p.cy, r = std::hypot(dx, dy);
        if (r == 0) return {x, y};
        const double s = p.distorted_radius(r) / r;
        return {p.cx + dx * s, p.cy + dy * s};
    }
    std::vector<cv::Point3d> ray{{(x - c.cx) / c.fx, (y - c.cy) / c.fy, 1.0}};
    std::vector<cv::Point2d> px;
    const cv::Mat zero = cv::Mat::zeros(3, 1, CV_64F);
    if (c.model == LensModel::kFisheye)
        cv::fisheye::projectPoints(ray, px, zero, zero, impl_->k, impl_->d);
    else
        cv::projectPoints(ray, zero, zero, impl_->k, impl_->d, px);
    return {px[0].x, px[0].y};
}

bool Undistorter::init(const Calibration& c, std::string& error) {
    auto impl = std::make_unique<Impl>();
    impl->cal = c;
    if (c.width <= 0 || c.height <= 0) {
        error = "calibration has no image size";
        return false;
    }
    if (c.model == LensModel::kBook && !impl->cal.book)
        impl->cal.book = RadialPolynomial{c.distortion, c.cx, c.cy};
    impl->k = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
    impl->d = cv::Mat(c.distortion, true);
    const cv::Size size(c.width, c.height);
    cv::Mat fx(size, CV_32FC1), fy(size, CV_32FC1);
    try {
        if (c.model == LensModel::kBook) {
            const RadialPolynomial& p = *impl->cal.book;
            const double r_max =
                std::hypot(std::max(p.cx, c.width - p.cx), std::max(p.cy, c.height - p.cy));
            if (!p.monotonic(c.fov.valid() ? c.fov.radius : r_max)) {
                error = "the book polynomial folds over inside the image: no inverse mapping";
                return false;
            }
            // Tabulate r -> r' once per integer radius, then interpolate: the per-pixel
            // cost is a sqrt and a lerp, not a polynomial.
            std::vector<float> ratio(static_cast<std::size_t>(r_max) + 3);
            for (std::size_t i = 0; i < ratio.size(); ++i)
                ratio[i] = i == 0 ? static_cast<float>(1.0 - p.k[0])
                                  : static_cast<float>(p.distorted_radius(i) / i);
            for (int y = 0; y < c.height; ++y)
                for (int x = 0; x < c.width; ++x) {
                    const double dx = x - p.cx, dy = y - p.cy, r = std::hypot(dx, dy);
                    const std::size_t i = static_cast<std::size_t>(r);
                    const double f = r - i;
                    const double s = ratio[i] * (1 - f) + ratio[i + 1] * f;
                    fx.at<float>(y, x) = static_cast<float>(p.cx + dx * s);
                    fy.at<float>(y, x) = static_cast<float>(p.cy + dy * s);
                }
        } else if (c.model == LensModel::kFisheye) {
            cv::fisheye::initUndistortRectifyMap(impl->k, impl->d, cv::Mat::eye(3, 3, CV_64F),
                                                 impl->k, size, CV_32FC1, fx, fy);
        } else {
            cv::initUndistortRectifyMap(impl->k, impl->d, cv::Mat(), impl->k, size, CV_32FC1, fx,
                                        fy);
        }
    } catch (const cv::Exception& e) {
        error = std::string("cannot build the undistortion maps: ") + e.what();
        return false;
    }
    // The field-of-view mask: sources outside the circle read the black border.
    if (c.fov.valid())
        for (int y = 0; y < c.height; ++y)
            for (int x = 0; x < c.width; ++x)
                if (!c.fov.contains(fx.at<float>(y, x), fy.at<float>(y, x)))
                    fx.at<float>(y, x) = -10.f;
    cv::convertMaps(fx, fy, impl->map_xy, impl->map_frac, CV_16SC2);
    for (int y = 0; y < c.height; ++y) {
        const cv::Vec2s* xy = impl->map_xy.ptr<cv::Vec2s>(y);
        int start = -1;
        for (int x = 0; x <= c.width; ++x) {
            const bool ok = x < c.width && fx.at<float>(y, x) > -1 && xy[x][0] >= 0 &&
                            xy[x][1] >= 0 && xy[x][0] <= c.width - 2 && xy[x][1] <= c.height - 2;
            if (ok && start < 0) start = x;
            if (!ok && start >= 0) impl->spans.push_back({y, start, x}), start = -1;
        }
    }
    // Halve the work by pixels, not rows: the field of view is a disc.
    std::size_t total = 0, acc = 0;
    for (const auto& sp : impl->spans) total += static_cast<std::size_t>(sp.x1 - sp.x0);
    impl->split_span = impl->spans.size();
    impl->split_row = c.height;
    for (std::size_t i = 0; i < impl->spans.size(); ++i) {
        if (2 * acc >= total && (i == 0 || impl->spans[i].y != impl->spans[i - 1].y)) {
            impl->split_span = i;
            impl->split_row = impl->spans[i].y;
            break;
        }
        acc += static_cast<std::size_t>(impl->spans[i].x1 - impl->spans[i].x0);
    }
    const int threads = impl_ ? this->threads() : 1;
    impl_ = std::move(impl);
    if (threads == 2) set_threads(2);
    return true;
}

bool Undistorter::apply(const hal::Frame& in, hal::Frame& out) const {
    if (!impl_ || !(in.format == out.format) || in.format.width != impl_->cal.width ||
        in.format.height != impl_->cal.height || in.data == nullptr || out.data == nullptr)
        return false;
    int type = 0;
    switch (in.format.pixel_format) {
        case hal::PixelFormat::kBgr24:
        case hal::PixelFormat::kRgb24:
            type = CV_8UC3;
            break;
        case hal::PixelFormat::kBgra32:
            type = CV_8UC4;
            break;
        case hal::PixelFormat::kGray8:
            type = CV_8UC1;
            break;
        default:
            return false;
    }
    Impl& m = *impl_;
    if (m.helper) {
        {
            std::lock_guard lock(m.helper->mutex);
            m.helper->in = &in;
            m.helper->out = &out;
            m.helper->type = type;
            ++m.helper->posted;
        }
        m.helper->cv.notify_all();
        remap_part(m, type, in, out, 0, m.split_span, 0, m.split_row);
        std::unique_lock lock(m.helper->mutex);
        m.helper->cv.wait(lock, [&] { return m.helper->done == m.helper->posted; });
    } else {
        remap_part(m, type, in, out, 0, m.spans.size(), 0, in.format.height);
    }
    return true;
}

}  // namespace endotower::calibration
