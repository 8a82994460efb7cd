#include "endotower/calibration/undistorter.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <system_error>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define ENDOTOWER_HAVE_AVX2_KERNEL 1
#endif
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "endotower/app/helper_thread.hpp"

namespace endotower::calibration {

struct Undistorter::Impl {
    Calibration cal;
    // The map, sampled every 2^node_shift corrected pixels along each row: source (x, y)
    // in 1/65536 px. Between nodes the source is linear in x (expand_run): at the usual
    // 8 px, 1 byte per pixel to stream instead of 6, which is what the remap is bound by.
    // init() takes the widest step (8, 4, 2, 1) whose interpolation stays within
    // kMaxNodeError of the exact map on every pixel it remaps.
    static constexpr int kMaxNodeShift = 3;
    int node_shift = kMaxNodeShift;
    std::vector<std::int32_t> nodes;
    int node_stride = 0;  // int32 per row
    // Per thread (caller, helper): one row of the expanded fixed-point map, OpenCV's
    // layout: integer source (x, y) and 5-bit fractions (fy << 5 | fx).
    struct RowMap {
        std::vector<cv::Vec2s> xy;
        std::vector<std::uint16_t> frac;
    };
    RowMap row_maps[2];
    std::size_t map_rejected = 0;  // pixels black only because of the interpolation error
    double max_map_error = 0;      // px, over the remapped pixels (5-bit rounding included)
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
    Kernel kernel = Kernel::kScalar;  // resolved: never kBest

    // The helper thread that remaps the second half (set_threads(2)); started once. The
    // job's arguments are the frames of the apply() that posted it.
    std::unique_ptr<app::HelperThread> helper;
    const hal::Frame* job_in = nullptr;
    hal::Frame* job_out = nullptr;
    int job_type = 0;
};

namespace {

// The interpolated map may differ from the exact one by this much (px) on a remapped
// pixel, the 1/64 px of the 5-bit fractions included; real scopes stay far below it.
constexpr double kMaxNodeError = 0.05;

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

#if defined(ENDOTOWER_HAVE_AVX2_KERNEL)
// Whole 8-pixel node segments of a row, x0 a multiple of 8 (node step 8). Per segment
// the eight sources come from the two nodes in int32 lanes, with expand_run's integer
// arithmetic, as byte offsets and 5-bit fractions; then two pixels per step, one per
// 128-bit lane. Vertical blend first: the top and bottom taps interleaved byte by byte
// and multiplied by (32 - fy, fy) with maddubs (at most 255 * 32, no saturation), then
// the two horizontal taps of each channel paired by a shuffle and blended by
// (32 - fx, fx) with madd. The products are exact integers, so the sum and its
// rounding are the scalar loop's, bit for bit. Returns where it stopped: the partial
// segment at the end, or a segment whose 8-byte tap loads would pass the frame's end,
// is left to the caller.
template <int C>
__attribute__((target("avx2"))) int remap_segments_avx2(const Undistorter::Impl& m,
                                                        const hal::Frame& in, int y,
                                                        std::uint8_t* row, int x, int x1, int w) {
    struct Tables {
        alignas(16) std::uint8_t wy[32][16];  // bytes: 32 - fy, fy, ...
        alignas(16) std::int16_t wx[32][8];   // words: 32 - fx, fx, ...
        Tables() {
            for (int f = 0; f < 32; ++f) {
                for (int i = 0; i < 16; i += 2) {
                    wy[f][i] = static_cast<std::uint8_t>(32 - f);
                    wy[f][i + 1] = static_cast<std::uint8_t>(f);
                }
                for (int i = 0; i < 8; i += 2) {
                    wx[f][i] = static_cast<std::int16_t>(32 - f);
                    wx[f][i + 1] = static_cast<std::int16_t>(f);
                }
            }
        }
    };
    static const Tables t;
    // After maddubs a lane holds tap 0's channels then tap 1's (16-bit words); pair them
    // per channel: C == 3 words 0,3 1,4 2,5; C == 4 words 0,4 1,5 2,6 3,7.
    const __m256i pair =
        C == 3 ? _mm256_setr_epi8(0, 1, 6, 7, 2, 3, 8, 9, 4, 5, 10, 11, 12, 13, 14, 15, 0, 1, 6, 7,
                                  2, 3, 8, 9, 4, 5, 10, 11, 12, 13, 14, 15)
               : _mm256_setr_epi8(0, 1, 8, 9, 2, 3, 10, 11, 4, 5, 12, 13, 6, 7, 14, 15, 0, 1, 8, 9,
                                  2, 3, 10, 11, 4, 5, 12, 13, 6, 7, 14, 15);
    const __m256i round = _mm256_set1_epi32(512), half = _mm256_set1_epi32(1024),
                  f31 = _mm256_set1_epi32(31), lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const int ss = static_cast<int>(in.format.stride);
    const __m256i vss = _mm256_set1_epi32(ss);
    // The last offset whose two 8-byte tap loads stay inside the frame's pixels.
    const __m256i last_ok =
        _mm256_set1_epi32((in.format.height - 1) * ss + C * in.format.width - 8 - ss);
    const std::uint8_t* src = in.data;
    const std::int32_t* n = m.nodes.data() + static_cast<std::size_t>(y) * m.node_stride;
    alignas(32) std::int32_t off[8], frac[8];
    for (; x + 8 <= x1; x += 8) {
        const std::int32_t* a = n + 2 * (x >> 3);
        const __m256i sx =
            _mm256_add_epi32(_mm256_set1_epi32(a[0]),
                             _mm256_mullo_epi32(lane, _mm256_set1_epi32((a[2] - a[0]) >> 3)));
        const __m256i sy =
            _mm256_add_epi32(_mm256_set1_epi32(a[1]),
                             _mm256_mullo_epi32(lane, _mm256_set1_epi32((a[3] - a[1]) >> 3)));
        const __m256i qx = _mm256_srai_epi32(_mm256_add_epi32(sx, half), 11),
                      qy = _mm256_srai_epi32(_mm256_add_epi32(sy, half), 11);
        const __m256i ix = _mm256_srai_epi32(qx, 5), iy = _mm256_srai_epi32(qy, 5);
        const __m256i o = _mm256_add_epi32(
            _mm256_mullo_epi32(iy, vss),
            C == 4 ? _mm256_slli_epi32(ix, 2) : _mm256_add_epi32(_mm256_slli_epi32(ix, 1), ix));
        if (_mm256_movemask_epi8(_mm256_cmpgt_epi32(o, last_ok))) break;
        _mm256_store_si256(reinterpret_cast<__m256i*>(off), o);
        _mm256_store_si256(reinterpret_cast<__m256i*>(frac),
                           _mm256_or_si256(_mm256_slli_epi32(_mm256_and_si256(qy, f31), 5),
                                           _mm256_and_si256(qx, f31)));
        for (int j = 0; j < 8; j += 2) {
            const std::uint8_t* pa = src + off[j];
            const std::uint8_t* pb = src + off[j + 1];
            const __m128i top = _mm_castpd_si128(_mm_loadh_pd(
                _mm_castsi128_pd(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(pa))),
                reinterpret_cast<const double*>(pb)));
            const __m128i bot = _mm_castpd_si128(_mm_loadh_pd(
                _mm_castsi128_pd(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(pa + ss))),
                reinterpret_cast<const double*>(pb + ss)));
            const __m256i taps =
                _mm256_set_m128i(_mm_unpackhi_epi8(top, bot), _mm_unpacklo_epi8(top, bot));
            const int fa = frac[j], fb = frac[j + 1];
            const __m256i wy =
                _mm256_set_m128i(_mm_load_si128(reinterpret_cast<const __m128i*>(t.wy[fb >> 5])),
                                 _mm_load_si128(reinterpret_cast<const __m128i*>(t.wy[fa >> 5])));
            const __m256i wx =
                _mm256_set_m128i(_mm_load_si128(reinterpret_cast<const __m128i*>(t.wx[fb & 31])),
                                 _mm_load_si128(reinterpret_cast<const __m128i*>(t.wx[fa & 31])));
            __m256i v = _mm256_shuffle_epi8(_mm256_maddubs_epi16(taps, wy), pair);
            v = _mm256_srli_epi32(_mm256_add_epi32(_mm256_madd_epi16(v, wx), round), 10);
            v = _mm256_packus_epi16(_mm256_packs_epi32(v, v), v);
            const auto px_a = static_cast<std::uint32_t>(_mm256_cvtsi256_si32(v));
            const auto px_b =
                static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm256_extracti128_si256(v, 1)));
            // 4-byte stores: with C == 3 the extra byte lands on the next pixel, written
            // later (a's by b, b's by the next pair or the caller), except at the row's end.
            std::memcpy(row + C * (x + j), &px_a, 4);
            // NOLINTNEXTLINE(bugprone-branch-clone): the branches are the same only when C == 4
            if (C == 4 || x + j + 2 < w)
                std::memcpy(row + C * (x + j + 1), &px_b, 4);
            else
                std::memcpy(row + C * (x + j + 1), &px_b, C);
        }
    }
    return x;
}
#endif

#if defined(__SSE2__)
// (0, d, 2d, 3d) in int32 lanes.
inline __m128i lane_steps(std::int32_t d) {
    return _mm_setr_epi32(0, d, 2 * d, 3 * d);
}
#endif

// The fixed-point map of corrected pixels [x0, x1) of row y, from the row's nodes.
// The same integer arithmetic at init and per frame, so spans and pixels agree.
void expand_run(const Undistorter::Impl& m, int y, int x0, int x1, cv::Vec2s* xy,
                std::uint16_t* frac) {
    const int shift = m.node_shift, step = 1 << shift;
    const std::int32_t* n = m.nodes.data() + static_cast<std::size_t>(y) * m.node_stride;
    for (int x = x0; x < x1;) {
        // One node segment: the source advances by a constant step per pixel.
        const std::int32_t* a = n + 2 * (x >> shift);
        const std::int32_t dx = (a[2] - a[0]) >> shift, dy = (a[3] - a[1]) >> shift;
        const int j0 = x & (step - 1), end = std::min(x1, x - j0 + step);
        std::int32_t sx = a[0] + j0 * dx, sy = a[1] + j0 * dy;
#if defined(__SSE2__)
        // Four pixels at a time: the same integer steps and shifts, in lanes.
        if (x + 4 <= end) {
            __m128i vx = _mm_add_epi32(_mm_set1_epi32(sx), lane_steps(dx)),
                    vy = _mm_add_epi32(_mm_set1_epi32(sy), lane_steps(dy));
            const __m128i dx4 = _mm_set1_epi32(4 * dx), dy4 = _mm_set1_epi32(4 * dy),
                          half = _mm_set1_epi32(1024), f = _mm_set1_epi32(31);
            for (; x + 4 <= end; x += 4) {
                const __m128i qx = _mm_srai_epi32(_mm_add_epi32(vx, half), 11),
                              qy = _mm_srai_epi32(_mm_add_epi32(vy, half), 11);
                const __m128i ix = _mm_srai_epi32(qx, 5), iy = _mm_srai_epi32(qy, 5);
                const __m128i fr =
                    _mm_or_si128(_mm_slli_epi32(_mm_and_si128(qy, f), 5), _mm_and_si128(qx, f));
                _mm_storeu_si128(
                    reinterpret_cast<__m128i*>(xy + x),
                    _mm_packs_epi32(_mm_unpacklo_epi32(ix, iy), _mm_unpackhi_epi32(ix, iy)));
                _mm_storel_epi64(reinterpret_cast<__m128i*>(frac + x), _mm_packs_epi32(fr, fr));
                vx = _mm_add_epi32(vx, dx4);
                vy = _mm_add_epi32(vy, dy4);
            }
            sx = _mm_cvtsi128_si32(vx);
            sy = _mm_cvtsi128_si32(vy);
        }
#endif
        for (; x < end; ++x, sx += dx, sy += dy) {
            const std::int32_t qx = (sx + 1024) >> 11, qy = (sy + 1024) >> 11;  // 1/32 px
            xy[x] = cv::Vec2s(static_cast<short>(qx >> 5), static_cast<short>(qy >> 5));
            frac[x] = static_cast<std::uint16_t>(((qy & 31) << 5) | (qx & 31));
        }
    }
}

// The portable loop: pixels [x, x1) of a row from its row map.
template <int C>
void remap_pixels(const hal::Frame& in, const cv::Vec2s* xy, const std::uint16_t* fr,
                  std::uint8_t* row, int x, int x1) {
    const std::size_t ss = in.format.stride;
    for (; x < x1; ++x) {
        const std::uint8_t* p = in.data + static_cast<std::size_t>(xy[x][1]) * ss +
                                static_cast<std::size_t>(xy[x][0]) * C;
        const int fx = fr[x] & 31, fy = fr[x] >> 5;
        const int w00 = (32 - fx) * (32 - fy), w01 = fx * (32 - fy), w10 = (32 - fx) * fy,
                  w11 = fx * fy;
        std::uint8_t* o = row + C * x;
        for (int c = 0; c < C; ++c)
            o[c] = static_cast<std::uint8_t>(
                (p[c] * w00 + p[c + C] * w01 + p[ss + c] * w10 + p[ss + c + C] * w11 + 512) >> 10);
    }
}

// Remaps spans[first, last) and clears the other pixels of rows [row0, row1); `part`
// picks the thread's row map.
template <int C>
void remap_spans(const Undistorter::Impl& m, const hal::Frame& in, hal::Frame& out,
                 std::size_t first, std::size_t last, int row0, int row1, int part) {
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
        const Undistorter::Impl::RowMap& rm = m.row_maps[part];
        // The row map is the thread's own scratch; const Impl because apply() is const.
        auto* xy = const_cast<cv::Vec2s*>(rm.xy.data());
        auto* fr = const_cast<std::uint16_t*>(rm.frac.data());
        int x = sp.x0, x_end = sp.x1;
#if defined(ENDOTOWER_HAVE_AVX2_KERNEL)
        if constexpr (C == 3 || C == 4) {
            // The whole segments straight from the nodes; the head before the first
            // segment (remapped here first) and the tail after the last go the row-map way.
            const int seg = std::min(sp.x1, (sp.x0 + 7) & ~7);
            if (m.kernel == Undistorter::Kernel::kAvx2 && m.node_shift == 3 && seg + 8 <= sp.x1) {
                expand_run(m, y, x, seg, xy, fr);
                x = remap_run_sse2<C>(m, in, xy, fr, row, x, seg, w);
                remap_pixels<C>(in, xy, fr, row, x, seg);
                x = remap_segments_avx2<C>(m, in, y, row, seg, sp.x1, w);
            }
        }
#endif
        expand_run(m, y, x, x_end, xy, fr);
#if defined(__SSE2__)
        if constexpr (C == 3 || C == 4)
            if (m.kernel != Undistorter::Kernel::kScalar)
                x = remap_run_sse2<C>(m, in, xy, fr, row, x, x_end, w);
#endif
        remap_pixels<C>(in, xy, fr, row, x, x_end);
        x_done = sp.x1;
    }
    finish_row();
    for (; next_row < row1; ++next_row)
        std::memset(out.data + next_row * out.format.stride, 0, static_cast<std::size_t>(C) * w);
}

void remap_part(const Undistorter::Impl& m, int type, const hal::Frame& in, hal::Frame& out,
                std::size_t first, std::size_t last, int row0, int row1, int part) {
    switch (CV_ELEM_SIZE(type)) {
        case 1:
            remap_spans<1>(m, in, out, first, last, row0, row1, part);
            break;
        case 3:
            remap_spans<3>(m, in, out, first, last, row0, row1, part);
            break;
        default:
            remap_spans<4>(m, in, out, first, last, row0, row1, part);
            break;
    }
}

// The helper's half of apply(): the spans from split_span on.
void remap_second_half(void* impl) {
    const Undistorter::Impl& m = *static_cast<const Undistorter::Impl*>(impl);
    remap_part(m, m.job_type, *m.job_in, *m.job_out, m.split_span, m.spans.size(), m.split_row,
               m.job_in->format.height, 1);
}

// The runs of remapped pixels for the current nodes (see Impl::nodes). A corrected pixel
// is remapped when its four taps lie in the frame, its source lies in the field of view
// (else it reads black: the mask), and the interpolated map is within kMaxNodeError of
// the exact map (fx, fy); the rest is black.
void build_spans(Undistorter::Impl& m, const cv::Mat& fx, const cv::Mat& fy) {
    m.spans.clear();
    m.map_rejected = 0;
    m.max_map_error = 0;
    cv::Vec2s* xy = m.row_maps[0].xy.data();
    std::uint16_t* frac = m.row_maps[0].frac.data();
    for (int y = 0; y < m.cal.height; ++y) {
        expand_run(m, y, 0, m.cal.width, xy, frac);
        int start = -1;
        for (int x = 0; x <= m.cal.width; ++x) {
            bool ok = false;
            if (x < m.cal.width) {
                const float ex = fx.at<float>(y, x), ey = fy.at<float>(y, x);
                const double sx = xy[x][0] + (frac[x] & 31) / 32.0,
                             sy = xy[x][1] + (frac[x] >> 5) / 32.0;
                const bool taps = xy[x][0] >= 0 && xy[x][1] >= 0 && xy[x][0] <= m.cal.width - 2 &&
                                  xy[x][1] <= m.cal.height - 2;
                const bool in_fov = !m.cal.fov.valid() || m.cal.fov.contains(ex, ey);
                const double err = std::max(std::abs(sx - ex), std::abs(sy - ey));
                ok = taps && in_fov && err <= kMaxNodeError;
                if (taps && in_fov && !ok) ++m.map_rejected;
                m.max_map_error = ok ? std::max(m.max_map_error, err) : m.max_map_error;
            }
            if (ok && start < 0) start = x;
            if (!ok && start >= 0) m.spans.push_back({y, start, x}), start = -1;
        }
    }
}

}  // namespace

bool Undistorter::set_threads(int threads) {
    if (!impl_ || threads < 1 || threads > 2) return false;
    if (threads == 1) {
        impl_->helper.reset();  // joins the thread
        return true;
    }
    if (impl_->helper) return true;
    try {
        impl_->helper = std::make_unique<app::HelperThread>();
    } catch (const std::system_error&) {
        return false;  // no thread to be had (a process limit): apply() stays on one
    }
    return true;
}

namespace {
bool kernel_runs_here(Undistorter::Kernel k) {
#if defined(__SSE2__)
    constexpr bool sse2 = true;
#else
    constexpr bool sse2 = false;
#endif
    if (k == Undistorter::Kernel::kScalar) return true;
    if (k == Undistorter::Kernel::kSse2) return sse2;
#if defined(ENDOTOWER_HAVE_AVX2_KERNEL)
    if (k == Undistorter::Kernel::kAvx2) return __builtin_cpu_supports("avx2");
#endif
    return false;
}

Undistorter::Kernel best_kernel() {
    for (const auto k : {Undistorter::Kernel::kAvx2, Undistorter::Kernel::kSse2})
        if (kernel_runs_here(k)) return k;
    return Undistorter::Kernel::kScalar;
}
}  // namespace

bool Undistorter::set_kernel(Kernel k) {
    if (!impl_) return false;
    if (k == Kernel::kBest) k = best_kernel();
    if (!kernel_runs_here(k)) return false;
    impl_->kernel = k;
    return true;
}

Undistorter::Kernel Undistorter::kernel() const {
    return impl_ ? impl_->kernel : Kernel::kScalar;
}

int Undistorter::threads() const {
    return impl_ && impl_->helper ? 2 : 1;
}

Undistorter::Undistorter() = default;
Undistorter::~Undistorter() = default;
Undistorter::Undistorter(Undistorter&&) noexcept = default;
Undistorter& Undistorter::operator=(Undistorter&&) noexcept = default;

Undistorter::MapStats Undistorter::map_stats() const {
    MapStats s;
    if (!impl_) return s;
    s.max_error_px = impl_->max_map_error;
    s.node_step = 1 << impl_->node_shift;
    for (const auto& sp : impl_->spans) s.remapped += static_cast<std::size_t>(sp.x1 - sp.x0);
    return s;
}

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
    // OpenCV's models written out (cv::projectPoints allocates per call, and this runs
    // per tracked point per frame); the tilted-sensor model (14 coefficients) goes to
    // OpenCV.
    const double a = (x - c.cx) / c.fx, b = (y - c.cy) / c.fy, r2 = a * a + b * b;
    const std::vector<double>& k = c.distortion;
    auto coef = [&k](std::size_t i) { return i < k.size() ? k[i] : 0.0; };
    if (c.model == LensModel::kFisheye) {
        const double r = std::sqrt(r2), t = std::atan(r), t2 = t * t;
        const double td = t * (1 + t2 * (coef(0) + t2 * (coef(1) + t2 * (coef(2) + t2 * coef(3)))));
        const double s = r > 1e-12 ? td / r : 1.0;
        return {c.fx * a * s + c.cx, c.fy * b * s + c.cy};
    }
    if (k.size() <= 12) {
        const double radial = (1 + r2 * (coef(0) + r2 * (coef(1) + r2 * coef(4)))) /
                              (1 + r2 * (coef(5) + r2 * (coef(6) + r2 * coef(7))));
        const double u = a * radial + 2 * coef(2) * a * b + coef(3) * (r2 + 2 * a * a) +
                         r2 * (coef(8) + r2 * coef(9));
        const double v = b * radial + coef(2) * (r2 + 2 * b * b) + 2 * coef(3) * a * b +
                         r2 * (coef(10) + r2 * coef(11));
        return {c.fx * u + c.cx, c.fy * v + c.cy};
    }
    std::vector<cv::Point3d> ray{{a, b, 1.0}};
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
    // The exact map, one node column past the last pixel (nodes bracket every pixel).
    constexpr int max_step = 1 << Impl::kMaxNodeShift;
    const cv::Size size(((c.width + max_step - 1) / max_step) * max_step + 1, c.height);
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
            const double r_table =
                std::hypot(std::max(p.cx, size.width - p.cx), std::max(p.cy, c.height - p.cy));
            std::vector<float> ratio(static_cast<std::size_t>(r_table) + 3);
            for (std::size_t i = 0; i < ratio.size(); ++i)
                ratio[i] = i == 0 ? static_cast<float>(1.0 - p.k[0])
                                  : static_cast<float>(p.distorted_radius(i) / i);
            for (int y = 0; y < c.height; ++y)
                for (int x = 0; x < size.width; ++x) {
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
    for (auto& rm : impl->row_maps) {
        rm.xy.resize(static_cast<std::size_t>(c.width));
        rm.frac.resize(static_cast<std::size_t>(c.width));
    }
    // Sources far outside the frame (a pinhole map past its valid radius) are clamped so
    // the fixed point does not overflow; pixels near them are never remapped.
    auto fixed = [](float v) {
        return static_cast<std::int32_t>(std::lround(std::clamp(v, -16000.f, 16000.f) * 65536.f));
    };
    for (int shift = Impl::kMaxNodeShift; shift >= 0; --shift) {
        const int step = 1 << shift, nodes_per_row = (c.width + step - 1) / step + 1;
        impl->node_shift = shift;
        impl->node_stride = 2 * nodes_per_row;
        impl->nodes.assign(static_cast<std::size_t>(impl->node_stride) * c.height, 0);
        for (int y = 0; y < c.height; ++y) {
            std::int32_t* n = impl->nodes.data() + static_cast<std::size_t>(y) * impl->node_stride;
            for (int k = 0; k < nodes_per_row; ++k) {
                n[2 * k] = fixed(fx.at<float>(y, k * step));
                n[2 * k + 1] = fixed(fy.at<float>(y, k * step));
            }
        }
        build_spans(*impl, fx, fy);
        if (impl->map_rejected == 0) break;  // else a finer step (at 1, only rounding)
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
    impl->kernel = impl_ ? impl_->kernel : best_kernel();
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
        m.job_in = &in;
        m.job_out = &out;
        m.job_type = type;
        m.helper->post(remap_second_half, &m);
        remap_part(m, type, in, out, 0, m.split_span, 0, m.split_row, 0);
        m.helper->wait();
    } else {
        remap_part(m, type, in, out, 0, m.spans.size(), 0, in.format.height, 0);
    }
    return true;
}

}  // namespace endotower::calibration
