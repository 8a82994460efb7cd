#include "endotower/calibration/square_grid.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <queue>

#include "blob_centroid.hpp"

namespace endotower::calibration {

namespace {

double dist(Point2 a, Point2 b) {
    return std::hypot(a.x - b.x, a.y - b.y);
}

// Index of the centre nearest `p` within `tol`, or -1.
int nearest(const std::vector<Point2>& pts, Point2 p, double tol) {
    int best = -1;
    double bd = tol;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const double d = dist(pts[i], p);
        if (d < bd) bd = d, best = static_cast<int>(i);
    }
    return best;
}

}  // namespace

bool detect_square_centres(const GrayImage& image, const FovCircle& fov, std::vector<Point2>& out,
                           std::string& error) {
    const std::string where = image.name.empty() ? std::string("image") : image.name;
    const cv::Mat gray(image.height, image.width, CV_8UC1,
                       const_cast<std::uint8_t*>(image.pixels.data()));
    cv::Mat inside = cv::Mat::zeros(gray.size(), CV_8UC1);
    const double r_in = fov.radius * 0.98;
    cv::circle(inside, cv::Point(cvRound(fov.cx), cvRound(fov.cy)), cvRound(r_in), 255, cv::FILLED);
    // Otsu over the field of view only: the dark surround must not pull the threshold.
    std::vector<std::uint8_t> in_px;
    in_px.reserve(image.pixels.size());
    for (int y = 0; y < gray.rows; ++y)
        for (int x = 0; x < gray.cols; ++x)
            if (inside.at<std::uint8_t>(y, x)) in_px.push_back(gray.at<std::uint8_t>(y, x));
    if (in_px.empty()) {
        error = where + ": the field of view lies outside the image";
        return false;
    }
    cv::Mat dummy;
    const double t = cv::threshold(cv::Mat(in_px).reshape(1, 1), dummy, 0, 255,
                                   cv::THRESH_BINARY | cv::THRESH_OTSU);
    cv::Mat dark;
    cv::threshold(gray, dark, t, 255, cv::THRESH_BINARY_INV);
    dark &= inside;
    cv::Mat labels, stats, cents;
    const int n = cv::connectedComponentsWithStats(dark, labels, stats, cents, 8, CV_32S);
    std::vector<int> areas;
    for (int i = 1; i < n; ++i)
        if (stats.at<int>(i, cv::CC_STAT_AREA) >= 9)
            areas.push_back(stats.at<int>(i, cv::CC_STAT_AREA));
    if (areas.size() < 9) {
        error = where + ": grid not found (" + std::to_string(areas.size()) +
                " dark squares inside the field of view, need at least 9)";
        return false;
    }
    std::nth_element(areas.begin(), areas.begin() + areas.size() / 2, areas.end());
    const double median = areas[areas.size() / 2];
    out.clear();
    for (int i = 1; i < n; ++i) {
        const int area = stats.at<int>(i, cv::CC_STAT_AREA);
        if (area < median / 4 || area > median * 4) continue;
        Point2 c{cents.at<double>(i, 0), cents.at<double>(i, 1)};
        refine_dark_centroid(gray, labels, stats, i, c);
        // Squares cut by the field-of-view rim have a biased centroid.
        const double half_diag = std::sqrt(static_cast<double>(area) / 2.0) + 2.0;
        if (!fov.contains(c.x, c.y, fov.radius - r_in + half_diag)) continue;
        out.push_back(c);
    }
    if (out.size() < 9) {
        error = where + ": grid not found (" + std::to_string(out.size()) +
                " whole squares inside the field of view, need at least 9)";
        return false;
    }
    return true;
}

bool find_centre_squares(const std::vector<Point2>& centres, Point2 centre, CentreSquares& out,
                         std::string& error) {
    const int c0 = nearest(centres, centre, 1e18);
    if (c0 < 0) {
        error = "no squares";
        return false;
    }
    const Point2 o = centres[c0];
    // Nearest neighbours of the centre square give the two lattice directions.
    std::vector<std::pair<double, int>> by_d;
    for (std::size_t i = 0; i < centres.size(); ++i)
        if (static_cast<int>(i) != c0) by_d.push_back({dist(centres[i], o), static_cast<int>(i)});
    std::sort(by_d.begin(), by_d.end());
    Point2 u{}, v{};
    bool hu = false, hv = false;
    for (std::size_t k = 0; k < std::min<std::size_t>(by_d.size(), 8); ++k) {
        const Point2 d{centres[by_d[k].second].x - o.x, centres[by_d[k].second].y - o.y};
        if (by_d[k].first > 1.5 * by_d[0].first) break;
        if (!hu && std::abs(d.x) > 2 * std::abs(d.y))
            u = d.x > 0 ? d : Point2{-d.x, -d.y}, hu = true;
        if (!hv && std::abs(d.y) > 2 * std::abs(d.x))
            v = d.y > 0 ? d : Point2{-d.x, -d.y}, hv = true;
    }
    if (!hu || !hv) {
        error = "grid not found: the centre square has no horizontal and vertical neighbours";
        return false;
    }
    // The nine squares, then the least-squares lattice through them.
    Point2 sum{}, su{}, sv{};
    Point2 nine[3][3];
    for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i) {
            const Point2 pred{o.x + i * u.x + j * v.x, o.y + i * u.y + j * v.y};
            const int k = nearest(centres, pred, 0.3 * std::min(dist(u, {}), dist(v, {})));
            if (k < 0) {
                error = "grid not found: square (" + std::to_string(i) + ", " + std::to_string(j) +
                        ") of the nine central squares is missing";
                return false;
            }
            nine[j + 1][i + 1] = centres[k];
            sum.x += centres[k].x, sum.y += centres[k].y;
            su.x += i * centres[k].x, su.y += i * centres[k].y;
            sv.x += j * centres[k].x, sv.y += j * centres[k].y;
        }
    out.origin = {sum.x / 9, sum.y / 9};
    out.u = {su.x / 6, su.y / 6};
    out.v = {sv.x / 6, sv.y / 6};
    out.dx = dist(out.u, {});
    out.dy = dist(out.v, {});
    out.sx_over_sy = out.dx / out.dy;
    out.max_offset_px = 0;
    for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i) {
            const Point2 p{out.origin.x + i * out.u.x + j * out.v.x,
                           out.origin.y + i * out.u.y + j * out.v.y};
            out.max_offset_px = std::max(out.max_offset_px, dist(p, nine[j + 1][i + 1]));
        }
    return true;
}

std::vector<RadialSample> radial_samples(const std::vector<Point2>& centres,
                                         const CentreSquares& grid, Point2 c,
                                         std::vector<Point2>* measured,
                                         std::vector<Point2>* actual) {
    // Breadth-first from the centre square: each neighbour is predicted by continuing
    // the measured step that reached the current square (follows the barrel bend).
    std::map<std::pair<int, int>, int> index;  // (i, j) -> centre
    const int c0 = nearest(centres, grid.origin, 0.3 * std::min(grid.dx, grid.dy));
    std::vector<RadialSample> out;
    if (c0 < 0) return out;
    std::vector<bool> used(centres.size(), false);
    std::queue<std::pair<int, int>> todo;
    index[{0, 0}] = c0;
    used[c0] = true;
    todo.push({0, 0});
    const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
    while (!todo.empty()) {
        const auto [i, j] = todo.front();
        todo.pop();
        const Point2 p = centres[index[{i, j}]];
        for (int d = 0; d < 4; ++d) {
            const std::pair<int, int> next{i + di[d], j + dj[d]};
            if (index.count(next)) continue;
            Point2 step{di[d] * grid.u.x + dj[d] * grid.v.x, di[d] * grid.u.y + dj[d] * grid.v.y};
            const auto back = index.find({i - di[d], j - dj[d]});
            if (back != index.end())
                step = {p.x - centres[back->second].x, p.y - centres[back->second].y};
            const int k = nearest(centres, {p.x + step.x, p.y + step.y}, 0.3 * dist(step, {}));
            if (k < 0 || used[k]) continue;
            used[k] = true;
            index[next] = k;
            todo.push(next);
        }
    }
    for (const auto& [ij, k] : index) {
        const Point2 a{grid.origin.x + ij.first * grid.u.x + ij.second * grid.v.x,
                       grid.origin.y + ij.first * grid.u.y + ij.second * grid.v.y};
        const double r = dist(a, c), rm = dist(centres[k], c);
        out.push_back({r, r - rm});
        if (measured) measured->push_back(centres[k]);
        if (actual) actual->push_back(a);
    }
    return out;
}

bool fit_book_distortion(const std::vector<Point2>& centres, const CentreSquares& grid,
                         Point2 start, double search_px, int order, double r_max,
                         BookDistortion& out, std::string& error) {
    std::vector<Point2> measured, actual;
    radial_samples(centres, grid, start, &measured, &actual);
    if (static_cast<int>(measured.size()) < order + 1) {
        error = "too few points: " + std::to_string(measured.size()) +
                " squares on the grid for an order-" + std::to_string(order) + " fit";
        return false;
    }
    auto samples_about = [&](Point2 c) {
        std::vector<RadialSample> s(measured.size());
        for (std::size_t i = 0; i < measured.size(); ++i) {
            const double r = dist(actual[i], c);
            s[i] = {r, r - dist(measured[i], c)};
        }
        return s;
    };
    auto cost = [&](Point2 c) {
        RadialFit f;
        std::string e;
        return fit_radial_polynomial(samples_about(c), order, f, e, r_max) ? f.total_error : 1e300;
    };
    Point2 best = start;
    double best_cost = cost(start);
    for (const double step : {1.0, 0.05}) {
        const int n = step == 1.0 ? static_cast<int>(std::ceil(search_px)) : 20;
        const Point2 around = best;
        for (int j = -n; j <= n; ++j)
            for (int i = -n; i <= n; ++i) {
                const Point2 c{around.x + i * step, around.y + j * step};
                if (step == 1.0 && dist(c, start) > search_px) continue;
                const double v = cost(c);
                if (v < best_cost) best_cost = v, best = c;
            }
    }
    BookDistortion d;
    d.samples = samples_about(best);
    if (!fit_radial_polynomial(d.samples, order, d.fit, error, r_max)) return false;
    d.fit.poly.cx = best.x;
    d.fit.poly.cy = best.y;
    d.measured = std::move(measured);
    d.actual = std::move(actual);
    out = std::move(d);
    return true;
}

}  // namespace endotower::calibration
