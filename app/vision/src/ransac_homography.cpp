// RansacHomography (see the header): fixed-size Eigen maths, no buffers, no allocation.
#include "ransac_homography.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace endotower::vision::detail {

namespace {

using Mat3 = Eigen::Matrix3d;
using Vec2 = Eigen::Vector2d;

// Three sample points closer to a line than this (sine of the angle at the first) make
// a degenerate sample.
constexpr double kMinSine = 1e-4;

// Hartley normalisation: centroid to the origin, mean distance sqrt(2).
bool normaliser(std::span<const cv::Point2f> p, Mat3& t) {
    double cx = 0, cy = 0;
    for (const cv::Point2f& q : p) cx += q.x, cy += q.y;
    const auto n = static_cast<double>(p.size());
    cx /= n, cy /= n;
    double d = 0;
    for (const cv::Point2f& q : p) d += std::hypot(q.x - cx, q.y - cy);
    d /= n;
    if (!(d > 1e-12) || !std::isfinite(d)) return false;
    const double s = std::sqrt(2.0) / d;
    t << s, 0, -s * cx, 0, s, -s * cy, 0, 0, 1;
    return true;
}

Vec2 apply(const Mat3& t, const cv::Point2f& q) {
    return {t(0, 0) * q.x + t(0, 2), t(1, 1) * q.y + t(1, 2)};  // t is a normaliser
}

double cross(const Vec2& a, const Vec2& b, const Vec2& c) {
    const Vec2 u = b - a, v = c - a;
    return u.x() * v.y() - u.y() * v.x();
}

// No three of the four nearly collinear, in either set, and the orientations of the
// four triangles either all kept or all mirrored (OpenCV's subset check).
bool good_sample(const std::array<Vec2, 4>& a, const std::array<Vec2, 4>& b) {
    constexpr std::array<std::array<int, 3>, 4> kTriangles{
        {{0, 1, 2}, {1, 2, 3}, {2, 3, 0}, {3, 0, 1}}};
    int flipped = 0;
    for (const auto& t : kTriangles) {
        const double ca = cross(a[t[0]], a[t[1]], a[t[2]]), cb = cross(b[t[0]], b[t[1]], b[t[2]]);
        const double la = (a[t[1]] - a[t[0]]).norm() * (a[t[2]] - a[t[0]]).norm(),
                     lb = (b[t[1]] - b[t[0]]).norm() * (b[t[2]] - b[t[0]]).norm();
        if (!(std::abs(ca) > kMinSine * la) || !(std::abs(cb) > kMinSine * lb)) return false;
        flipped += (ca < 0) != (cb < 0) ? 1 : 0;
    }
    return flipped == 0 || flipped == 4;
}

// The 4-point DLT with h33 = 1 (normalised coordinates: the centroids map near each
// other, so h33 is far from 0).
bool solve4(const std::array<Vec2, 4>& a, const std::array<Vec2, 4>& b, Mat3& h) {
    Eigen::Matrix<double, 8, 8> m;
    Eigen::Matrix<double, 8, 1> r;
    for (int i = 0; i < 4; ++i) {
        const double x = a[i].x(), y = a[i].y(), u = b[i].x(), v = b[i].y();
        m.row(2 * i) << x, y, 1, 0, 0, 0, -u * x, -u * y;
        m.row(2 * i + 1) << 0, 0, 0, x, y, 1, -v * x, -v * y;
        r(2 * i) = u;
        r(2 * i + 1) = v;
    }
    const Eigen::PartialPivLU<Eigen::Matrix<double, 8, 8>> lu(m);
    if (!(lu.rcond() > 1e-12)) return false;
    const Eigen::Matrix<double, 8, 1> x = lu.solve(r);
    if (!x.allFinite()) return false;
    h << x(0), x(1), x(2), x(3), x(4), x(5), x(6), x(7), 1;
    return true;
}

// Squared reprojection distance of a pair under h (pixels), +inf when not finite.
double error2(const Mat3& h, const cv::Point2f& a, const cv::Point2f& b) {
    const double w = h(2, 0) * a.x + h(2, 1) * a.y + h(2, 2);
    const double x = (h(0, 0) * a.x + h(0, 1) * a.y + h(0, 2)) / w,
                 y = (h(1, 0) * a.x + h(1, 1) * a.y + h(1, 2)) / w;
    const double e = (x - b.x) * (x - b.x) + (y - b.y) * (y - b.y);
    return std::isfinite(e) ? e : std::numeric_limits<double>::infinity();
}

int count_inliers(const Mat3& h, std::span<const cv::Point2f> from, std::span<const cv::Point2f> to,
                  double t2) {
    int n = 0;
    for (std::size_t i = 0; i < from.size(); ++i) n += error2(h, from[i], to[i]) <= t2 ? 1 : 0;
    return n;
}

// Samples needed to draw one all-inlier sample with `confidence` (OpenCV's rule).
int needed_iterations(double confidence, double inlier_ratio, int max_iterations) {
    const double num = std::log(std::max(1 - confidence, std::numeric_limits<double>::min()));
    const double denom =
        std::log(std::max(1 - std::pow(inlier_ratio, 4), std::numeric_limits<double>::min()));
    if (denom >= 0 || -num >= max_iterations * -denom) return max_iterations;
    return static_cast<int>(std::lround(num / denom));
}

// splitmix64: small, fast, and the same sequence on every platform.
struct Rng {
    std::uint64_t state;
    std::uint64_t next() {
        std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return z ^ (z >> 31);
    }
    std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
};

// Normalised pixel pair i.
struct Pairs {
    std::span<const cv::Point2f> from, to;
    Mat3 ta, tb;
    Vec2 a(std::size_t i) const { return apply(ta, from[i]); }
    Vec2 b(std::size_t i) const { return apply(tb, to[i]); }
    // Back to pixels, scaled to h33 = 1; false when that is not possible.
    bool pixels(const Mat3& hn, Mat3& h) const {
        h = tb.inverse() * hn * ta;
        if (!(std::abs(h(2, 2)) > 1e-12) || !h.allFinite()) return false;
        h /= h(2, 2);
        return true;
    }
};

// Least squares over the inliers of `model` (in pixels): the DLT over all of them, then
// Levenberg-Marquardt on the reprojection error (normalised coordinates, h33 = 1).
bool refit(const Pairs& p, const Mat3& model, double t2, int iterations, Mat3& out) {
    Eigen::Matrix<double, 9, 9> ata = Eigen::Matrix<double, 9, 9>::Zero();
    for (std::size_t i = 0; i < p.from.size(); ++i) {
        if (!(error2(model, p.from[i], p.to[i]) <= t2)) continue;
        const Vec2 a = p.a(i), b = p.b(i);
        const double x = a.x(), y = a.y(), u = b.x(), v = b.y();
        Eigen::Matrix<double, 9, 1> r1, r2;
        r1 << x, y, 1, 0, 0, 0, -u * x, -u * y, -u;
        r2 << 0, 0, 0, x, y, 1, -v * x, -v * y, -v;
        ata.selfadjointView<Eigen::Lower>().rankUpdate(r1);
        ata.selfadjointView<Eigen::Lower>().rankUpdate(r2);
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(
        ata.selfadjointView<Eigen::Lower>());
    if (es.info() != Eigen::Success) return false;
    // A null space of more than one dimension: the inliers do not fix a homography.
    if (!(es.eigenvalues()(1) > 1e-9 * es.eigenvalues()(8))) return false;
    const Eigen::Matrix<double, 9, 1> e = es.eigenvectors().col(0);
    if (!(std::abs(e(8)) > 1e-12)) return false;
    Eigen::Matrix<double, 8, 1> h = e.head<8>() / e(8);

    const auto cost = [&](const Eigen::Matrix<double, 8, 1>& k, Eigen::Matrix<double, 8, 8>* jtj,
                          Eigen::Matrix<double, 8, 1>* jtr) {
        double c = 0;
        for (std::size_t i = 0; i < p.from.size(); ++i) {
            if (!(error2(model, p.from[i], p.to[i]) <= t2)) continue;
            const Vec2 a = p.a(i), b = p.b(i);
            const double x = a.x(), y = a.y();
            const double w = k(6) * x + k(7) * y + 1;
            const double px = (k(0) * x + k(1) * y + k(2)) / w,
                         py = (k(3) * x + k(4) * y + k(5)) / w;
            const double rx = px - b.x(), ry = py - b.y();
            c += rx * rx + ry * ry;
            if (jtj == nullptr) continue;
            Eigen::Matrix<double, 8, 1> jx, jy;
            jx << x / w, y / w, 1 / w, 0, 0, 0, -px * x / w, -px * y / w;
            jy << 0, 0, 0, x / w, y / w, 1 / w, -py * x / w, -py * y / w;
            jtj->selfadjointView<Eigen::Lower>().rankUpdate(jx);
            jtj->selfadjointView<Eigen::Lower>().rankUpdate(jy);
            *jtr += rx * jx + ry * jy;
        }
        return c;
    };
    double lambda = 1e-3, c = cost(h, nullptr, nullptr);
    for (int it = 0; it < iterations && std::isfinite(c); ++it) {
        Eigen::Matrix<double, 8, 8> jtj = Eigen::Matrix<double, 8, 8>::Zero();
        Eigen::Matrix<double, 8, 1> jtr = Eigen::Matrix<double, 8, 1>::Zero();
        cost(h, &jtj, &jtr);
        Eigen::Matrix<double, 8, 8> a = jtj.selfadjointView<Eigen::Lower>();
        a.diagonal() *= 1 + lambda;
        const Eigen::Matrix<double, 8, 1> step = a.ldlt().solve(-jtr);
        const Eigen::Matrix<double, 8, 1> next = h + step;
        const double cn = step.allFinite() ? cost(next, nullptr, nullptr) : c;
        if (cn < c) {
            const bool converged = c - cn < 1e-12 * (1 + c);
            h = next, c = cn, lambda = std::max(lambda / 10, 1e-9);
            if (converged) break;
        } else {
            lambda *= 10;
        }
    }
    Mat3 hn;
    hn << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), 1;
    return p.pixels(hn, out);
}

}  // namespace

bool RansacHomography::fit(std::span<const cv::Point2f> from, std::span<const cv::Point2f> to,
                           cv::Matx33d& h, std::span<std::uint8_t> inliers) {
    iterations_ = 0;
    const std::size_t n = from.size();
    if (n < 4 || to.size() != n || inliers.size() != n) return false;
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(from[i].x) || !std::isfinite(from[i].y) || !std::isfinite(to[i].x) ||
            !std::isfinite(to[i].y))
            return false;
    Pairs p{from, to, Mat3::Identity(), Mat3::Identity()};
    if (!normaliser(from, p.ta) || !normaliser(to, p.tb)) return false;
    const double t2 = p_.threshold_px * p_.threshold_px;
    Rng rng{p_.seed};
    Mat3 best;
    int best_count = 0;
    int needed = p_.max_iterations;
    for (int it = 0; it < needed; ++it) {
        ++iterations_;
        std::array<std::size_t, 4> idx{};
        for (std::size_t k = 0; k < 4; ++k) {
            bool fresh = false;
            while (!fresh) {
                idx[k] = rng.below(n);
                fresh = std::find(idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(k),
                                  idx[k]) == idx.begin() + static_cast<std::ptrdiff_t>(k);
            }
        }
        std::array<Vec2, 4> a, b;
        for (std::size_t k = 0; k < 4; ++k) a[k] = p.a(idx[k]), b[k] = p.b(idx[k]);
        Mat3 hn, hp;
        if (!good_sample(a, b) || !solve4(a, b, hn) || !p.pixels(hn, hp)) continue;
        const int count = count_inliers(hp, from, to, t2);
        if (count <= best_count) continue;
        best = hp, best_count = count;
        needed = std::min(needed,
                          needed_iterations(p_.confidence, static_cast<double>(count) / n, needed));
    }
    if (best_count < 4) return false;
    // The final least-squares refit of the sample's inliers serves unless it explains
    // fewer pairs than the sample did. (Refitting again while the inliers grow took in
    // points drifting under rotation on the simulator suites: one refit, as OpenCV.)
    Mat3 chosen = best, fitted;
    if (refit(p, best, t2, p_.refine_iterations, fitted) &&
        count_inliers(fitted, from, to, t2) >= best_count)
        chosen = fitted;
    if (!(std::abs(chosen.determinant()) > 1e-12)) return false;
    inlier_count_ = 0;
    for (std::size_t i = 0; i < n; ++i) {
        inliers[i] = error2(chosen, from[i], to[i]) <= t2 ? 1 : 0;
        inlier_count_ += inliers[i];
    }
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) h(r, c) = chosen(r, c);
    return true;
}

}  // namespace endotower::vision::detail
