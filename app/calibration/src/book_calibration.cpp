#include "endotower/calibration/book_calibration.hpp"

#include <cmath>
#include <opencv2/calib3d.hpp>

#include "endotower/calibration/target.hpp"

namespace endotower::calibration {

namespace {

bool same_size(const GrayImage& a, const GrayImage& b, std::string& error) {
    if (a.width == b.width && a.height == b.height) return true;
    error = b.name + ": image size " + std::to_string(b.width) + "x" + std::to_string(b.height) +
            " differs from " + a.name + " (" + std::to_string(a.width) + "x" +
            std::to_string(a.height) + "): mixed sizes";
    return false;
}

}  // namespace

double BookResult::radial_rms_px() const {
    const std::size_t n = distortion.samples.size();
    return n ? std::sqrt(2.0 * distortion.fit.total_error / n) : 0;
}

Calibration BookResult::calibration(const std::string& scope) const {
    Calibration c;
    c.scope = scope;
    c.model = LensModel::kBook;
    c.width = width;
    c.height = height;
    c.fx = fx;
    c.fy = fy;
    c.cx = distortion.fit.poly.cx;
    c.cy = distortion.fit.poly.cy;
    c.distortion = distortion.fit.poly.k;
    c.rms = radial_rms_px();
    c.fov = fov;
    c.book = distortion.fit.poly;
    c.separation = separation;
    return c;
}

bool run_book_calibration(const BookInputs& in, BookResult& out, std::string& error) {
    BookResult res;
    if (in.white.empty()) {
        error =
            "the book's procedure needs white-background images (--white DIR) for the image centre";
        return false;
    }
    const GrayImage& first = in.white.front();
    res.width = first.width;
    res.height = first.height;
    std::vector<FovCircle> circles;
    for (const GrayImage& w : in.white) {
        if (!same_size(first, w, error)) return false;
        FovCircle c;
        if (!detect_fov_circle(w, c, error)) return false;
        circles.push_back(c);
        res.fov.cx += c.cx / in.white.size();
        res.fov.cy += c.cy / in.white.size();
        res.fov.radius += c.radius / in.white.size();
    }
    for (const FovCircle& c : circles)
        res.fov_spread_px =
            std::max(res.fov_spread_px, std::hypot(c.cx - res.fov.cx, c.cy - res.fov.cy));
    // Square centres of every chart image.
    std::vector<std::vector<Point2>> centres(in.chart.size());
    std::vector<CentreSquares> grids(in.chart.size());
    int ref = -1, most = -1;
    for (std::size_t i = 0; i < in.chart.size(); ++i) {
        const GrayImage& g = in.chart[i].image;
        if (!same_size(first, g, error)) return false;
        if (!detect_square_centres(g, res.fov, centres[i], error)) return false;
        if (!find_centre_squares(centres[i], {res.fov.cx, res.fov.cy}, grids[i], error)) {
            error = g.name + ": " + error;
            return false;
        }
        if (ref < 0 && std::abs(in.chart[i].distance_mm - in.reference_mm) < 1e-9)
            ref = static_cast<int>(i);
        if (most < 0 || centres[i].size() > centres[most].size()) most = static_cast<int>(i);
    }
    if (ref < 0) {
        error = "no chart image at the reference distance " + std::to_string(in.reference_mm) +
                " mm (name one e.g. " + std::to_string(static_cast<int>(in.reference_mm)) +
                "mm.png)";
        return false;
    }
    res.reference = grids[ref];
    res.fx = focal_from_spacing(grids[ref].dx, in.pitch_mm, in.reference_mm);
    res.fy = focal_from_spacing(grids[ref].dy, in.pitch_mm, in.reference_mm);
    for (std::size_t i = 0; i < in.chart.size(); ++i)
        if (in.chart[i].distance_mm > 0)
            res.distances.push_back({in.chart[i].image.name, in.chart[i].distance_mm,
                                     distance_from_spacing(grids[i].dx, in.pitch_mm, res.fx)});
    if (!fit_book_distortion(centres[most], grids[most], {res.fov.cx, res.fov.cy},
                             0.05 * res.fov.radius, in.order, res.fov.radius, res.distortion,
                             error)) {
        error = in.chart[most].image.name + ": " + error;
        return false;
    }
    res.distortion_image = in.chart[most].image.name;
    if (!in.marker.empty()) {
        std::vector<std::pair<double, double>> rows;
        for (const DistanceImage& m : in.marker) {
            if (!same_size(first, m.image, error)) return false;
            if (!(m.distance_mm > 0)) {
                error = m.image.name + ": no distance in the file name (e.g. 070mm.png)";
                return false;
            }
            Point2 a, b;
            if (!detect_two_dots(m.image, res.fov, a, b, error)) return false;
            rows.push_back({m.distance_mm, std::hypot(a.x - b.x, a.y - b.y)});
        }
        std::sort(rows.begin(), rows.end());
        SeparationTable t;
        t.marker_mm = in.marker_mm;
        for (const auto& [z, s] : rows) {
            t.distances_mm.push_back(z);
            t.separation_px.push_back(s);
            res.pinhole_px.push_back(pinhole_separation(res.fx, in.marker_mm, z));
        }
        if (!t.validate(error)) return false;
        res.separation = t;
    }
    out = std::move(res);
    return true;
}

bool opencv_chart_distance(const Calibration& camera, const GrayImage& chart, const FovCircle& fov,
                           double pitch_mm, double& z_mm, std::string& error) {
    std::vector<Point2> centres;
    if (!detect_square_centres(chart, fov, centres, error)) return false;
    std::vector<cv::Point2f> pts, und;
    for (const Point2& p : centres) pts.emplace_back(p.x, p.y);
    const cv::Mat k =
        (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
    const cv::Mat d(camera.distortion, true);
    if (camera.model == LensModel::kFisheye)
        cv::fisheye::undistortPoints(pts, und, k, d, cv::noArray(), k);
    else
        cv::undistortPoints(pts, und, k, d, cv::noArray(), k);
    std::vector<Point2> u;
    for (const cv::Point2f& p : und) u.push_back({p.x, p.y});
    CentreSquares g;
    if (!find_centre_squares(u, {fov.cx, fov.cy}, g, error)) {
        error = chart.name + ": " + error;
        return false;
    }
    z_mm = distance_from_spacing(g.dx, pitch_mm, camera.fx);
    return true;
}

double book_reprojection_rms(const std::vector<View>& views, const Calibration& book) {
    const RadialPolynomial& p = *book.book;
    const cv::Mat k = (cv::Mat_<double>(3, 3) << book.fx, 0, p.cx, 0, book.fy, p.cy, 0, 0, 1);
    double ss = 0;
    std::size_t n = 0;
    for (const View& v : views) {
        std::vector<cv::Point3f> obj;
        std::vector<cv::Point2f> corrected;
        for (const Point3& o : v.object_points) obj.emplace_back(o.x, o.y, o.z);
        bool ok = true;
        for (const Point2& q : v.image_points) {
            const double dx = q.x - p.cx, dy = q.y - p.cy, rd = std::hypot(dx, dy);
            double r = 0;
            if (rd > 0 && !p.corrected_radius(rd, r)) ok = false;
            const double s = rd > 0 ? r / rd : 1;
            corrected.emplace_back(p.cx + dx * s, p.cy + dy * s);
        }
        cv::Mat rv, tv;
        if (!ok || !cv::solvePnP(obj, corrected, k, cv::Mat(), rv, tv)) continue;
        std::vector<cv::Point2f> proj;
        cv::projectPoints(obj, rv, tv, k, cv::Mat(), proj);
        for (std::size_t i = 0; i < proj.size(); ++i) {
            const double dx = proj[i].x - p.cx, dy = proj[i].y - p.cy, r = std::hypot(dx, dy);
            const double s = r > 0 ? p.distorted_radius(r) / r : 1;
            const double ex = p.cx + dx * s - v.image_points[i].x,
                         ey = p.cy + dy * s - v.image_points[i].y;
            ss += ex * ex + ey * ey;
            ++n;
        }
    }
    return n ? std::sqrt(ss / n) : -1;
}

}  // namespace endotower::calibration
