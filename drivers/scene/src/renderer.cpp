#include "endotower/scene/renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "rng.hpp"
#include "truth_compute.hpp"
#include "world.hpp"

namespace endotower::scene {

using namespace detail;

namespace {

constexpr double kGain = 1.45;    // exposure: tissue at kRefMm, light 1 -> mid grey-ish
constexpr double kRefMm = 110.0;  // distance at which the illumination is 1
constexpr int kLut = 4096;

inline double pow2n(double c, int n) {  // c^(2^n)
    for (int i = 0; i < n; ++i) c *= c;
    return c;
}

}  // namespace

struct SceneRenderer::Impl {
    SceneModel model;
    std::vector<float> rays;        // unit ray per pixel, 3 floats; z = 0 where there is none
    std::vector<float> weight;      // vignetting x field-of-view mask
    std::vector<int> span0, span1;  // per row, the columns with weight > 0
    cv::Mat rad, blurred, smoke;
    std::vector<std::uint16_t> ids;
    std::vector<std::uint8_t> edge;
    std::uint8_t lut[kLut];
    // Sensor noise added to a byte for each sum of four random bytes (0 .. 1020).
    std::array<int, 1021> noise_step{};

    bool init(const Scenario& s, std::uint64_t seed, std::string& error);
    Vec3 ray_at(double x, double y) const;
    int shade(const FrameWorld& w, Vec3 d, float out[3]) const;
    void shade_plane(const FrameWorld& w, Vec3 d, double t, float out[3], int& id) const;
    void shade_object(const FrameWorld& w, const Hit& h, Vec3 d, float out[3]) const;
    void render(int index, Image& image, FrameTruth& truth);
};

bool SceneRenderer::Impl::init(const Scenario& s, std::uint64_t seed, std::string& error) {
    if (!model.init(s, seed, error)) return false;
    const CameraModel& c = model.cam;
    const int w = c.width, h = c.height;
    rays.assign(static_cast<std::size_t>(w) * h * 3, 0.0f);
    weight.assign(static_cast<std::size_t>(w) * h, 0.0f);
    span0.assign(h, w);
    span1.assign(h, -1);
    const double rmax = c.max_undistorted_radius();
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * w + x;
            double xu, yu;
            if (!c.undistort(x, y, xu, yu) || std::hypot(xu - c.cx, yu - c.cy) > rmax) continue;
            const Vec3 d = normalized(c.ray(xu, yu));
            rays[3 * i] = static_cast<float>(d.x);
            rays[3 * i + 1] = static_cast<float>(d.y);
            rays[3 * i + 2] = static_cast<float>(d.z);
            // Soft 1.5 px rim of the illuminated circle; vignetting falls off towards it.
            const double r = std::hypot(x - c.fov_cx, y - c.fov_cy);
            const double rim = std::clamp((c.fov_radius - r) / 1.5 + 0.5, 0.0, 1.0);
            const double q = r / c.fov_radius;
            weight[i] = static_cast<float>(rim * (1 - c.vignetting * q * q * (0.6 + 0.4 * q * q)));
            if (weight[i] > 0) {
                span0[y] = std::min(span0[y], x);
                span1[y] = std::max(span1[y], x);
            }
        }
    }
    rad.create(h, w, CV_32FC3);
    ids.assign(static_cast<std::size_t>(w) * h, 0);
    edge.assign(static_cast<std::size_t>(w) * h, 0);
    for (int i = 0; i < kLut; ++i) {
        const double v = static_cast<double>(i) / (kLut - 1);
        const double srgb = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
        lut[i] = static_cast<std::uint8_t>(std::lround(std::clamp(srgb, 0.0, 1.0) * 255));
    }
    const double sigma = model.sc.noise / 147.8;  // four bytes sum: sd 147.8, near-Gaussian
    for (int sum = 0; sum <= 1020; ++sum)
        noise_step[static_cast<std::size_t>(sum)] =
            static_cast<int>(std::lround((sum - 510) * sigma));
    if (s.smoke > 0) {
        // Screen-space haze: smooth noise twice the frame, scrolled over time.
        Rng rng(stream_seed(seed, kTagSmoke));
        cv::Mat acc = cv::Mat::zeros(2 * h, 2 * w, CV_32F);
        for (double cell : {0.35, 0.15, 0.06}) {
            const int gw = static_cast<int>(2 * w / (cell * h)) + 2,
                      gh = static_cast<int>(2 / cell) + 2;
            cv::Mat g(gh, gw, CV_32F), up;
            for (int y = 0; y < gh; ++y)
                for (int x = 0; x < gw; ++x) g.at<float>(y, x) = static_cast<float>(rng.uniform());
            cv::resize(g, up, acc.size(), 0, 0, cv::INTER_CUBIC);
            acc += up * (cell * 2.2);
        }
        cv::normalize(acc, smoke, 0, 1, cv::NORM_MINMAX);
    }
    return true;
}

Vec3 SceneRenderer::Impl::ray_at(double x, double y) const {
    // Bilinear between the stored pixel rays: the inverse distortion is smooth.
    const int w = model.cam.width, h = model.cam.height;
    const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, w - 2),
              y0 = std::clamp(static_cast<int>(std::floor(y)), 0, h - 2);
    const double fx = x - x0, fy = y - y0;
    Vec3 r[4];
    for (int k = 0; k < 4; ++k) {
        const std::size_t i = (static_cast<std::size_t>(y0 + k / 2) * w + x0 + k % 2) * 3;
        r[k] = {rays[i], rays[i + 1], rays[i + 2]};
        if (r[k].z == 0) {  // at the edge of the mapped area: the nearest pixel's ray
            const std::size_t j =
                (static_cast<std::size_t>(std::clamp<long>(std::lround(y), 0, h - 1)) * w +
                 static_cast<std::size_t>(std::clamp<long>(std::lround(x), 0, w - 1))) *
                3;
            return {rays[j], rays[j + 1], rays[j + 2]};
        }
    }
    return normalized(lerp(lerp(r[0], r[1], fx), lerp(r[2], r[3], fx), fy));
}

void SceneRenderer::Impl::shade_plane(const FrameWorld& w, Vec3 d, double t, float out[3],
                                      int& id) const {
    const Vec3 p = t * d;
    const double u = dot(p - w.po, w.pe1), v = dot(p - w.po, w.pe2);
    const double e = w.light * w.exposure * kGain * (kRefMm / t) * (kRefMm / t);
    if (w.target) {
        const TargetSpec& ts = model.sc.target;
        bool black = false;
        double paper = 0.82;
        switch (ts.kind) {
            case TargetKind::kSquares: {
                const double i = std::round(u / ts.pitch_mm + (ts.cols - 1) / 2.0),
                             j = std::round(v / ts.pitch_mm + (ts.rows - 1) / 2.0);
                if (i >= 0 && i < ts.cols && j >= 0 && j < ts.rows) {
                    const double cu = (i - (ts.cols - 1) / 2.0) * ts.pitch_mm,
                                 cv = (j - (ts.rows - 1) / 2.0) * ts.pitch_mm;
                    black = std::abs(u - cu) < ts.size_mm / 2 && std::abs(v - cv) < ts.size_mm / 2;
                }
                break;
            }
            case TargetKind::kCheckerboard: {
                const double a = u / ts.pitch_mm + (ts.cols + 1) / 2.0,
                             b = v / ts.pitch_mm + (ts.rows + 1) / 2.0;
                if (a >= 0 && a < ts.cols + 1 && b >= 0 && b < ts.rows + 1)
                    black =
                        (static_cast<int>(std::floor(a)) + static_cast<int>(std::floor(b))) % 2 ==
                        0;
                break;
            }
            case TargetKind::kTwoDot: {
                const double s = ts.separation_mm / 2, r2 = ts.dot_mm * ts.dot_mm / 4;
                black = (u - s) * (u - s) + v * v < r2 || (u + s) * (u + s) + v * v < r2;
                break;
            }
            case TargetKind::kGridLines: {
                paper = 0.035;  // black paper with light lines (book fig. 3.3b)
                const double du = std::abs(u - std::round(u / ts.pitch_mm) * ts.pitch_mm);
                const double dv = std::abs(v - std::round(v / ts.pitch_mm) * ts.pitch_mm);
                black = du < ts.line_mm / 2 || dv < ts.line_mm / 2;  // "black" = the other tone
                break;
            }
            default:
                break;
        }
        const double alb =
            ts.kind == TargetKind::kGridLines ? (black ? 0.7 : paper) : (black ? 0.035 : paper);
        const double c = std::max(0.0, -dot(w.pn, d));
        const float v0 = static_cast<float>(e * alb * (0.3 + 0.7 * c));
        out[0] = v0 * 0.97f;
        out[1] = v0;
        out[2] = v0 * 1.02f;
        id = black ? 2 : 1;
        return;
    }
    double tu = u, tv = v;  // the tissue point seen here
    if (w.deform > 0) model.undeform(tu, tv, w.deform);
    TexSample s = model.tex.sample(tu, tv);
    if (w.background > 0 && !model.tex2.empty() && !model.inside_regions(tu, tv)) {
        const TexSample o = model.tex2.sample(tu, tv);
        const float b = static_cast<float>(w.background);
        s = {s.b + b * (o.b - s.b),       s.g + b * (o.g - s.g),    s.r + b * (o.r - s.r),
             s.wet + b * (o.wet - s.wet), s.gu + b * (o.gu - s.gu), s.gv + b * (o.gv - s.gv)};
    }
    const Vec3 n =
        normalized(w.pn - static_cast<double>(s.gu) * w.pe1 - static_cast<double>(s.gv) * w.pe2);
    const double c = std::max(0.0, -dot(n, d));
    const double diffuse = 0.35 + 0.65 * c;
    const double spec = s.wet * (1.8 * pow2n(c, 7) + 0.06 * pow2n(c, 3));
    out[0] = static_cast<float>(e * (s.b * diffuse + spec));
    out[1] = static_cast<float>(e * (s.g * diffuse + spec));
    out[2] = static_cast<float>(e * (s.r * diffuse + spec));
    id = 0;
}

void SceneRenderer::Impl::shade_object(const FrameWorld& w, const Hit& h, Vec3 d,
                                       float out[3]) const {
    if (h.flat != nullptr) {
        for (int k = 0; k < 3; ++k) out[k] = h.flat[k];
        return;
    }
    const double e = w.light * w.exposure * kGain * std::min(60.0, (kRefMm / h.t) * (kRefMm / h.t));
    const double c = std::max(0.0, -dot(h.n, d));
    double alb[3], spec = 0;
    Surface s = h.surface;
    if (s == Surface::kShaft && h.mat == Material::kMetal) s = Surface::kMetal;
    switch (s) {
        case Surface::kShaft:  // black insulated shaft: a soft sheen and a narrow streak
            alb[0] = 0.014, alb[1] = 0.014, alb[2] = 0.016;
            spec = 0.05 * pow2n(c, 3) + 0.22 * pow2n(c, 6);
            break;
        case Surface::kStrip:
            alb[0] = alb[1] = alb[2] = 0.010;
            spec = 0.02 * pow2n(c, 3);
            break;
        case Surface::kMetal:
        case Surface::kJaw: {  // steel, tinted by the tissue it reflects
            const double serr = h.serrated && h.along > 1.0
                                    ? 0.8 + 0.2 * (std::sin(2 * M_PI * h.along / 0.6) > 0 ? 1 : 0)
                                    : 1.0;
            alb[0] = (0.045 + 0.04 * (1 - c)) * serr;
            alb[1] = (0.042 + 0.03 * (1 - c)) * serr;
            alb[2] = (0.05 + 0.10 * (1 - c)) * serr;
            spec = (0.8 * pow2n(c, 6) + 0.12 * pow2n(c, 2)) * serr;
            break;
        }
        case Surface::kFlap: {
            const Vec3 p = h.t * d;
            const TexSample t = model.tex.empty()
                                    ? TexSample{0.1f, 0.05f, 0.35f, 0.5f, 0, 0}
                                    : model.tex.sample(p.x * 1.3 + 517, p.y * 1.3 + 311);
            const Vec3 n = normalized(h.n - 0.5 * Vec3{t.gu, t.gv, 0});
            const double cc = std::max(0.0, -dot(n, d));
            alb[0] = t.b, alb[1] = t.g, alb[2] = t.r;
            for (double& a : alb) a *= 0.35 + 0.65 * cc;
            spec = t.wet * 1.5 * pow2n(cc, 7);
            for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(e * (alb[k] + spec));
            return;
        }
        default:
            alb[0] = alb[1] = alb[2] = 0;
    }
    for (int k = 0; k < 3; ++k)
        out[k] = static_cast<float>(e * (alb[k] * (0.25 + 0.75 * c) + spec));
}

int SceneRenderer::Impl::shade(const FrameWorld& w, Vec3 d, float out[3]) const {
    const CameraModel& cam = model.cam;
    if (d.z <= 1e-9) {
        out[0] = out[1] = out[2] = 0;
        return 0;
    }
    const float xu = static_cast<float>(cam.cx + cam.fx * d.x / d.z),
                yu = static_cast<float>(cam.cy + cam.fy * d.y / d.z);
    const double tp = w.plane_t(d);
    const Hit h = w.trace(d, xu, yu);
    if (h.t < tp) {
        shade_object(w, h, d, out);
        return h.id;
    }
    int id = 0;
    if (std::isfinite(tp)) {
        shade_plane(w, d, tp, out, id);
    } else {
        out[0] = out[1] = out[2] = 0;
    }
    return id;
}

void SceneRenderer::Impl::render(int index, Image& image, FrameTruth& truth) {
    const Scenario& sc = model.sc;
    const CameraModel& cam = model.cam;
    const int w = cam.width, h = cam.height;
    const double t = model.time_of(index);
    const FrameWorld world = model.world_at(t, index);

    // Motion blur: sub-frame instants across the exposure where things move.
    std::vector<FrameWorld> subs;
    Box dynamic;
    bool all_dynamic = false;
    if (sc.motion_blur > 0) {
        const double exposure = sc.motion_blur / sc.fps;
        const FrameWorld a = model.world_at(t - exposure / 2, index),
                         b = model.world_at(t + exposure / 2, index);
        double disp = 0;
        auto shift = [&](Vec3 p, Vec3 q) {
            double x0, y0, x1, y1;
            if (cam.project_undistorted(p, x0, y0) && cam.project_undistorted(q, x1, y1))
                disp = std::max(disp, std::hypot(x1 - x0, y1 - y0));
        };
        for (std::size_t i = 0; i < a.tools.size(); ++i) {
            shift(a.tools[i].pose.tip, b.tools[i].pose.tip);
            shift(a.tools[i].pose.head, b.tools[i].pose.head);
        }
        for (std::size_t i = 0; i < a.caps.size(); ++i) shift(a.caps[i].b, b.caps[i].b);
        all_dynamic = model.endoscope.moving();
        if (all_dynamic)
            shift(a.cam.to_camera(b.cam.c + 100.0 * (b.cam.r_wc * Vec3{0, 0, 1})), Vec3{0, 0, 100});
        const int m = std::clamp(static_cast<int>(std::ceil(disp / 0.7)), 1, 24);
        if (m > 1) {
            for (int j = 0; j < m; ++j) {
                subs.push_back(model.world_at(t + ((j + 0.5) / m - 0.5) * exposure, index));
                for (const Shaft& s : subs.back().shafts) dynamic.add(s.box);
                for (const Capsule& c : subs.back().caps) dynamic.add(c.box);
                for (const Flap& f : subs.back().flaps) dynamic.add(f.box);
            }
        }
    }

    rad.setTo(cv::Scalar::all(0));
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
        for (int y = rows.start; y < rows.end; ++y) {
            float* out = rad.ptr<float>(y);
            for (int x = span0[y]; x <= span1[y]; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * w + x;
                const Vec3 d{rays[3 * i], rays[3 * i + 1], rays[3 * i + 2]};
                if (d.z == 0) continue;
                const float xu = static_cast<float>(cam.cx + cam.fx * d.x / d.z),
                            yu = static_cast<float>(cam.cy + cam.fy * d.y / d.z);
                if (!subs.empty() && (all_dynamic || dynamic.contains(xu, yu))) {
                    // Unchanged surface at both ends of the exposure and mid-way: the
                    // pixel is not swept by an edge; one sample does.
                    float acc[3] = {0, 0, 0}, o[3];
                    const int id = shade(world, d, out + 3 * x);
                    if (shade(subs.front(), d, o) == id && shade(subs.back(), d, o) == id) {
                        ids[i] = static_cast<std::uint16_t>(id);
                        continue;
                    }
                    const int m = static_cast<int>(subs.size());
                    for (int j = 0; j < m; ++j) {
                        // Stratified sub-pixel positions: the blur is anti-aliased too.
                        const double ox = std::fmod(j * 0.6180339887, 1.0) - 0.5,
                                     oy = (j + 0.5) / m - 0.5;
                        shade(subs[j], ray_at(x + ox, y + oy), o);
                        for (int k = 0; k < 3; ++k) acc[k] += o[k];
                    }
                    for (int k = 0; k < 3; ++k) out[3 * x + k] = acc[k] / m;
                    ids[i] = 0xFFFF;  // no edge pass here
                    continue;
                }
                ids[i] = static_cast<std::uint16_t>(shade(world, d, out + 3 * x));
            }
        }
    });

    // Anti-aliasing: pixels whose surface differs from a neighbour's get 3x3 samples.
    std::fill(edge.begin(), edge.end(), 0);
    for (int y = 0; y + 1 < h; ++y)
        for (int x = std::max(0, span0[y]); x < std::min(w - 1, span1[y] + 1); ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * w + x;
            if (weight[i] <= 0 || ids[i] == 0xFFFF) continue;
            if (ids[i] != ids[i + 1] && ids[i + 1] != 0xFFFF) edge[i] = edge[i + 1] = 1;
            if (ids[i] != ids[i + w] && ids[i + w] != 0xFFFF) edge[i] = edge[i + w] = 1;
        }
    cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
        for (int y = rows.start; y < rows.end; ++y) {
            float* out = rad.ptr<float>(y);
            for (int x = span0[y]; x <= span1[y]; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * w + x;
                if (!edge[i] || rays[3 * i + 2] == 0) continue;
                float acc[3] = {0, 0, 0}, o[3];
                for (int sy = -1; sy <= 1; ++sy)
                    for (int sx = -1; sx <= 1; ++sx) {
                        shade(world, ray_at(x + sx / 3.0, y + sy / 3.0), o);
                        for (int k = 0; k < 3; ++k) acc[k] += o[k];
                    }
                for (int k = 0; k < 3; ++k) out[3 * x + k] = acc[k] / 9;
            }
        }
    });

    // Optics and disturbances in linear light, then the tone curve.
    Rng flash_rng(stream_seed(model.seed, kTagFlash, static_cast<std::uint64_t>(index)));
    const bool flash = sc.flash_rate > 0 && flash_rng.uniform() < sc.flash_rate;
    double fx0 = 0, fy0 = 0, fsig = 1, fstr = 0;
    if (flash) {
        const double a = flash_rng.uniform(0, 2 * M_PI),
                     r = std::sqrt(flash_rng.uniform()) * 0.7 * cam.fov_radius;
        fx0 = cam.fov_cx + r * std::cos(a);
        fy0 = cam.fov_cy + r * std::sin(a);
        fsig = flash_rng.uniform(0.04, 0.12) * h;
        fstr = flash_rng.uniform(2.0, 5.0);
    }
    const double smoke_k = index >= sc.smoke_from_frame ? sc.smoke : 0.0;
    const int sox = static_cast<int>(std::lround(t * 0.05 * w)) % w,
              soy = static_cast<int>(std::lround(t * 0.03 * h)) % h;
    const float haze[3] = {0.62f, 0.60f, 0.60f};
    for (int y = 0; y < h; ++y) {
        float* p = rad.ptr<float>(y);
        for (int x = 0; x < w; ++x, p += 3) {
            const float wt = weight[static_cast<std::size_t>(y) * w + x];
            if (wt <= 0) {
                p[0] = p[1] = p[2] = 0;
                continue;
            }
            if (smoke_k > 0) {
                const float s = static_cast<float>(
                    std::min(1.0, smoke_k * 1.3 * smoke.at<float>(y + soy, x + sox)));
                for (int k = 0; k < 3; ++k)
                    p[k] +=
                        s *
                        (haze[k] * static_cast<float>(world.light * world.exposure * kGain) * 0.8f -
                         p[k]);
            }
            if (flash) {
                const double d2 = (x - fx0) * (x - fx0) + (y - fy0) * (y - fy0);
                const float f = static_cast<float>(fstr * std::exp(-d2 / (2 * fsig * fsig)));
                for (int k = 0; k < 3; ++k) p[k] += f;
            }
            for (int k = 0; k < 3; ++k) p[k] = 1.0f - std::exp(-p[k] * wt);
        }
    }
    const cv::Mat* src = &rad;
    if (cam.blur_sigma > 0.05) {
        cv::GaussianBlur(rad, blurred, cv::Size(0, 0), cam.blur_sigma, cam.blur_sigma,
                         cv::BORDER_REFLECT);
        src = &blurred;
    }
    image.width = w;
    image.height = h;
    image.bgr.resize(static_cast<std::size_t>(w) * h * 3);
    const bool noisy = sc.noise > 0;
    std::uint64_t bits = 0;
    int left = 0;
    std::mt19937_64 eng(stream_seed(model.seed, kTagNoise, static_cast<std::uint64_t>(index)));
    for (int y = 0; y < h; ++y) {
        const float* p = src->ptr<float>(y);
        std::uint8_t* o = image.bgr.data() + static_cast<std::size_t>(y) * w * 3;
        for (int x = 0; x < 3 * w; ++x) {
            // Per pixel: truncating x + 0.5 is the cheap rounding, and it is clamped.
            // NOLINTNEXTLINE(bugprone-incorrect-roundings)
            int v = lut[std::clamp(static_cast<int>(p[x] * (kLut - 1) + 0.5f), 0, kLut - 1)];
            if (noisy) {
                if (left == 0) {
                    bits = eng();
                    left = 2;
                }
                const int sum = static_cast<int>((bits & 0xFF) + ((bits >> 8) & 0xFF) +
                                                 ((bits >> 16) & 0xFF) + ((bits >> 24) & 0xFF));
                bits >>= 32;
                --left;
                v += noise_step[static_cast<std::size_t>(sum)];
            }
            o[x] = static_cast<std::uint8_t>(std::clamp(v, 0, 255));
        }
    }
    compute_truth(model, world, index, truth);
}

void SceneRenderer::tool_labels(std::vector<std::uint8_t>& out) const {
    const std::vector<std::uint16_t>& ids = impl_->ids;
    const std::vector<float>& weight = impl_->weight;
    out.resize(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
        const int id = ids[i];
        // Tool surfaces are 10 + 8 * tool + (0..7) (world.cpp); distractors from 100.
        if (weight[i] <= 0)
            out[i] = 0;
        else if (id == 0xFFFF)
            out[i] = kMixedLabel;
        else
            out[i] = id >= 10 && id < 100 ? static_cast<std::uint8_t>((id - 10) / 8 + 1) : 0;
    }
}

SceneRenderer::SceneRenderer() : impl_(std::make_unique<Impl>()) {}
SceneRenderer::~SceneRenderer() = default;
bool SceneRenderer::init(const Scenario& s, std::uint64_t seed, std::string& error) {
    return impl_->init(s, seed, error);
}
const CameraModel& SceneRenderer::camera() const {
    return impl_->model.cam;
}
const Scenario& SceneRenderer::scenario() const {
    return impl_->model.sc;
}
int SceneRenderer::frames() const {
    return impl_->model.sc.frames;
}
void SceneRenderer::render(int index, Image& image, FrameTruth& truth) {
    impl_->render(index, image, truth);
}

}  // namespace endotower::scene
