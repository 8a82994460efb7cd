#include "endotower/calibration/zhang_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>

namespace endotower::calibration {

namespace {

using Obj = std::vector<std::vector<cv::Point3f>>;
using Img = std::vector<std::vector<cv::Point2f>>;

struct Fit {
    cv::Mat k, d;
    std::vector<cv::Mat> rvecs, tvecs;
    double rms = 0;
};

void to_cv(const std::vector<View>& views, const std::vector<int>& use, Obj& obj, Img& img) {
    obj.clear();
    img.clear();
    for (int i : use) {
        std::vector<cv::Point3f> o;
        std::vector<cv::Point2f> p;
        for (const Point3& q : views[i].object_points) o.emplace_back(q.x, q.y, q.z);
        for (const Point2& q : views[i].image_points) p.emplace_back(q.x, q.y);
        obj.push_back(std::move(o));
        img.push_back(std::move(p));
    }
}

// `guess`: start from these intrinsics (the leave-one-out fits start from the fit
// with every view: same minimum, a fraction of the iterations).
bool run_fit(const std::vector<View>& views, const std::vector<int>& use, cv::Size size,
             LensModel model, const ZhangOptions& options, Fit& fit, std::string& error,
             const Fit* guess = nullptr) {
    Obj obj;
    Img img;
    to_cv(views, use, obj, img);
    try {
        fit.k = guess ? guess->k.clone() : cv::Mat::eye(3, 3, CV_64F);
        if (model == LensModel::kFisheye) {
            fit.d = guess ? guess->d.clone() : cv::Mat::zeros(4, 1, CV_64F);
            std::vector<cv::Mat> o64, i64;
            for (std::size_t v = 0; v < obj.size(); ++v) {
                cv::Mat o, i;
                cv::Mat(obj[v]).convertTo(o, CV_64FC3);
                cv::Mat(img[v]).convertTo(i, CV_64FC2);
                o64.push_back(o.reshape(3, 1));
                i64.push_back(i.reshape(2, 1));
            }
            fit.rms = cv::fisheye::calibrate(
                o64, i64, size, fit.k, fit.d, fit.rvecs, fit.tvecs,
                cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW |
                    (guess ? cv::fisheye::CALIB_USE_INTRINSIC_GUESS : 0),
                cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-9));
        } else {
            fit.d = guess ? guess->d.clone() : cv::Mat::zeros(5, 1, CV_64F);
            fit.rms = cv::calibrateCamera(obj, img, size, fit.k, fit.d, fit.rvecs, fit.tvecs,
                                          (options.zero_tangent ? cv::CALIB_ZERO_TANGENT_DIST : 0) |
                                              (guess ? cv::CALIB_USE_INTRINSIC_GUESS : 0));
        }
    } catch (const cv::Exception& e) {
        error = std::string("OpenCV calibration failed: ") + e.what();
        return false;
    }
    if (!std::isfinite(fit.rms)) {
        error = "OpenCV calibration failed: no finite solution";
        return false;
    }
    return true;
}

void project(const std::vector<cv::Point3f>& obj, const cv::Mat& r, const cv::Mat& t,
             const cv::Mat& k, const cv::Mat& d, LensModel model, std::vector<cv::Point2f>& out) {
    if (model == LensModel::kFisheye) {
        std::vector<cv::Point3d> o(obj.begin(), obj.end());
        std::vector<cv::Point2d> p;
        cv::fisheye::projectPoints(o, p, r, t, k, d);
        out.assign(p.begin(), p.end());
    } else {
        cv::projectPoints(obj, r, t, k, d, out);
    }
}

// Pose of one view under fixed intrinsics.
bool solve_pose(const std::vector<cv::Point3f>& obj, const std::vector<cv::Point2f>& img,
                const cv::Mat& k, const cv::Mat& d, LensModel model, cv::Mat& r, cv::Mat& t) {
    try {
        if (model == LensModel::kFisheye) {
            std::vector<cv::Point2f> und;
            cv::fisheye::undistortPoints(img, und, k, d);
            return cv::solvePnP(obj, und, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), r, t);
        }
        return cv::solvePnP(obj, img, k, d, r, t);
    } catch (const cv::Exception&) {
        return false;
    }
}

double view_rms(const std::vector<cv::Point3f>& obj, const std::vector<cv::Point2f>& img,
                const cv::Mat& r, const cv::Mat& t, const cv::Mat& k, const cv::Mat& d,
                LensModel model) {
    std::vector<cv::Point2f> p;
    project(obj, r, t, k, d, model, p);
    double ss = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const double dx = p[i].x - img[i].x, dy = p[i].y - img[i].y;
        ss += dx * dx + dy * dy;
    }
    return std::sqrt(ss / std::max<std::size_t>(1, p.size()));
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
}

std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3f", v);
    return b;
}

}  // namespace

const char* to_string(LensModel m) {
    switch (m) {
        case LensModel::kPinhole:
            return "pinhole";
        case LensModel::kFisheye:
            return "fisheye";
        case LensModel::kBook:
            return "book";
    }
    return "pinhole";
}

bool parse_lens_model(const std::string& s, LensModel& out) {
    if (s == "pinhole")
        out = LensModel::kPinhole;
    else if (s == "fisheye")
        out = LensModel::kFisheye;
    else if (s == "book")
        out = LensModel::kBook;
    else
        return false;
    return true;
}

bool calibrate_zhang(const std::vector<View>& views, int width, int height, LensModel model,
                     ZhangResult& out, std::string& error, ZhangOptions options) {
    if (model == LensModel::kBook) {
        error = "the book's model is not an OpenCV calibration";
        return false;
    }
    for (const View& v : views)
        if (v.image_points.size() < 6 || v.image_points.size() != v.object_points.size()) {
            error =
                v.name + ": too few points (" + std::to_string(v.image_points.size()) + ", need 6)";
            return false;
        }
    if (views.size() < 3) {
        error = "too few views: the target was found in " + std::to_string(views.size()) +
                " image(s), need at least 3";
        return false;
    }
    const cv::Size size(width, height);
    std::vector<int> use(views.size());
    for (std::size_t i = 0; i < views.size(); ++i) use[i] = static_cast<int>(i);
    ZhangResult result;
    Fit fit;
    if (!run_fit(views, use, size, model, options, fit, error)) return false;
    while (options.reject_inconsistent && use.size() >= 4) {
        // Suspects: views whose error in the joint fit exceeds twice the median (at most
        // the three worst). Each is left out in turn; the one whose absence helps most
        // is tested below. No suspect, nothing to drop.
        std::vector<std::pair<double, std::size_t>> per_view;
        {
            Obj o;
            Img i;
            to_cv(views, use, o, i);
            for (std::size_t j = 0; j < use.size(); ++j)
                per_view.push_back(
                    {view_rms(o[j], i[j], fit.rvecs[j], fit.tvecs[j], fit.k, fit.d, model), j});
        }
        std::vector<double> errs;
        for (const auto& pv : per_view) errs.push_back(pv.first);
        const double joint_median = median(errs);
        std::sort(per_view.rbegin(), per_view.rend());
        int worst = -1;
        Fit best;
        for (std::size_t c = 0; c < std::min<std::size_t>(3, per_view.size()); ++c) {
            if (!(per_view[c].first > 2 * joint_median)) break;
            const std::size_t j = per_view[c].second;
            std::vector<int> rest = use;
            rest.erase(rest.begin() + j);
            Fit f;
            std::string e;
            if (!run_fit(views, rest, size, model, options, f, e, &fit)) continue;
            if (worst < 0 || f.rms < best.rms) worst = static_cast<int>(j), best = f;
        }
        if (worst < 0 || best.rms > fit.rms * (2.0 / 3.0)) break;
        // Its error under the others' calibration, against theirs.
        Obj obj;
        Img img;
        to_cv(views, use, obj, img);
        cv::Mat r, t;
        if (!solve_pose(obj[worst], img[worst], best.k, best.d, model, r, t)) break;
        const double own = view_rms(obj[worst], img[worst], r, t, best.k, best.d, model);
        std::vector<double> others;
        for (std::size_t j = 0, m = 0; j < use.size(); ++j) {
            if (static_cast<int>(j) == worst) continue;
            others.push_back(
                view_rms(obj[j], img[j], best.rvecs[m], best.tvecs[m], best.k, best.d, model));
            ++m;
        }
        const double med = median(others);
        if (!(own > 3 * med && own > 0.5)) break;
        result.dropped.push_back(
            {views[use[worst]].name, "inconsistent detection: RMS " + fmt(own) +
                                         " px under the other views' calibration (their median " +
                                         fmt(med) + " px); without it the RMS falls from " +
                                         fmt(fit.rms) + " to " + fmt(best.rms) + " px"});
        use.erase(use.begin() + worst);
        fit = best;
    }
    const double fmax = 10.0 * std::max(width, height);
    if (fit.k.at<double>(0, 0) > fmax || fit.k.at<double>(1, 1) > fmax) {
        char b[200];
        std::snprintf(b, sizeof b,
                      "implausible focal length fx %.0f fy %.0f px for %dx%d images (RMS %.3f px): "
                      "the target layout "
                      "does not match the grid; check --target and --spacing",
                      fit.k.at<double>(0, 0), fit.k.at<double>(1, 1), width, height, fit.rms);
        error = b;
        return false;
    }
    Obj obj;
    Img img;
    to_cv(views, use, obj, img);
    result.model = model;
    result.width = width;
    result.height = height;
    result.fx = fit.k.at<double>(0, 0);
    result.fy = fit.k.at<double>(1, 1);
    result.cx = fit.k.at<double>(0, 2);
    result.cy = fit.k.at<double>(1, 2);
    result.distortion.assign(fit.d.begin<double>(), fit.d.end<double>());
    result.rms = fit.rms;
    double spacing_sum = 0;
    int spacing_n = 0;
    for (std::size_t v = 0; v < use.size(); ++v) {
        result.views.push_back({views[use[v]].name, view_rms(obj[v], img[v], fit.rvecs[v],
                                                             fit.tvecs[v], fit.k, fit.d, model)});
        // Back-project onto the target plane: undistort to normalised rays, intersect.
        std::vector<cv::Point2f> und;
        if (model == LensModel::kFisheye)
            cv::fisheye::undistortPoints(img[v], und, fit.k, fit.d);
        else
            cv::undistortPoints(img[v], und, fit.k, fit.d);
        cv::Mat rot;
        cv::Rodrigues(fit.rvecs[v], rot);
        const cv::Vec3d n(rot.at<double>(0, 2), rot.at<double>(1, 2), rot.at<double>(2, 2));
        const cv::Vec3d t(fit.tvecs[v].at<double>(0), fit.tvecs[v].at<double>(1),
                          fit.tvecs[v].at<double>(2));
        std::vector<cv::Vec3d> pts;
        for (const cv::Point2f& u : und) {
            const cv::Vec3d ray(u.x, u.y, 1.0);
            pts.push_back(ray * (n.dot(t) / n.dot(ray)));
        }
        // Every pair of target points closer than 1.6 x the smallest spacing: neighbours.
        const auto& o = obj[v];
        double dmin = 1e30;
        for (std::size_t a = 1; a < o.size(); ++a) dmin = std::min(dmin, cv::norm(o[a] - o[0]));
        for (std::size_t a = 0; a < o.size(); ++a)
            for (std::size_t b = a + 1; b < o.size(); ++b) {
                const double truth = cv::norm(o[a] - o[b]);
                if (truth > 1.6 * dmin) continue;
                spacing_sum += std::abs(cv::norm(pts[a] - pts[b]) - truth);
                ++spacing_n;
            }
    }
    result.spacing_error = spacing_n ? spacing_sum / spacing_n : 0;
    out = result;
    return true;
}

double reprojection_rms(const std::vector<View>& views, const ZhangResult& camera) {
    cv::Mat k =
        (cv::Mat_<double>(3, 3) << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
    cv::Mat d(camera.distortion, true);
    Obj obj;
    Img img;
    std::vector<int> all(views.size());
    for (std::size_t i = 0; i < views.size(); ++i) all[i] = static_cast<int>(i);
    to_cv(views, all, obj, img);
    double ss = 0;
    std::size_t n = 0;
    for (std::size_t v = 0; v < obj.size(); ++v) {
        cv::Mat r, t;
        if (!solve_pose(obj[v], img[v], k, d, camera.model, r, t)) continue;
        const double e = view_rms(obj[v], img[v], r, t, k, d, camera.model);
        ss += e * e * obj[v].size();
        n += obj[v].size();
    }
    return n ? std::sqrt(ss / n) : -1;
}

}  // namespace endotower::calibration
