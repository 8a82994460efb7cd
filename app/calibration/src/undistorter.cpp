#include "endotower/calibration/undistorter.hpp"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace endotower::calibration {

struct Undistorter::Impl {
    Calibration cal;
    cv::Mat map_xy, map_frac;  // fixed point
    cv::Mat k, d;
};

Undistorter::Undistorter() = default;
Undistorter::~Undistorter() = default;
Undistorter::Undistorter(Undistorter&&) noexcept = default;
Undistorter& Undistorter::operator=(Undistorter&&) noexcept = default;

int Undistorter::width() const { return impl_ ? impl_->cal.width : 0; }
int Undistorter::height() const { return impl_ ? impl_->cal.height : 0; }

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
    if (c.model == LensModel::kFisheye) cv::fisheye::projectPoints(ray, px, zero, zero, impl_->k, impl_->d);
    else cv::projectPoints(ray, zero, zero, impl_->k, impl_->d, px);
    return {px[0].x, px[0].y};
}

bool Undistorter::init(const Calibration& c, std::string& error) {
    auto impl = std::make_unique<Impl>();
    impl->cal = c;
    if (c.width <= 0 || c.height <= 0) {
        error = "calibration has no image size";
        return false;
    }
    if (c.model == LensModel::kBook && !impl->cal.book) impl->cal.book = RadialPolynomial{c.distortion, c.cx, c.cy};
    impl->k = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
    impl->d = cv::Mat(c.distortion, true);
    const cv::Size size(c.width, c.height);
    cv::Mat fx(size, CV_32FC1), fy(size, CV_32FC1);
    try {
        if (c.model == LensModel::kBook) {
            const RadialPolynomial& p = *impl->cal.book;
            const double r_max = std::hypot(std::max(p.cx, c.width - p.cx), std::max(p.cy, c.height - p.cy));
            if (!p.monotonic(c.fov.valid() ? c.fov.radius : r_max)) {
                error = "the book polynomial folds over inside the image: no inverse mapping";
                return false;
            }
            // Tabulate r -> r' once per integer radius, then interpolate: the per-pixel
            // cost is a sqrt and a lerp, not a polynomial.
            std::vector<float> ratio(static_cast<std::size_t>(r_max) + 3);
            for (std::size_t i = 0; i < ratio.size(); ++i)
                ratio[i] = i == 0 ? static_cast<float>(1.0 - p.k[0]) : static_cast<float>(p.distorted_radius(i) / i);
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
            cv::fisheye::initUndistortRectifyMap(impl->k, impl->d, cv::Mat::eye(3, 3, CV_64F), impl->k, size, CV_32FC1,
                                                 fx, fy);
        } else {
            cv::initUndistortRectifyMap(impl->k, impl->d, cv::Mat(), impl->k, size, CV_32FC1, fx, fy);
        }
    } catch (const cv::Exception& e) {
        error = std::string("cannot build the undistortion maps: ") + e.what();
        return false;
    }
    // The field-of-view mask: sources outside the circle read the black border.
    if (c.fov.valid())
        for (int y = 0; y < c.height; ++y)
            for (int x = 0; x < c.width; ++x)
                if (!c.fov.contains(fx.at<float>(y, x), fy.at<float>(y, x))) fx.at<float>(y, x) = -10.f;
    cv::convertMaps(fx, fy, impl->map_xy, impl->map_frac, CV_16SC2);
    impl_ = std::move(impl);
    return true;
}

bool Undistorter::apply(const hal::Frame& in, hal::Frame& out) const {
    if (!impl_ || !(in.format == out.format) || in.format.width != impl_->cal.width ||
        in.format.height != impl_->cal.height || in.data == nullptr || out.data == nullptr)
        return false;
    int type = 0;
    switch (in.format.pixel_format) {
        case hal::PixelFormat::kBgr24:
        case hal::PixelFormat::kRgb24: type = CV_8UC3; break;
        case hal::PixelFormat::kBgra32: type = CV_8UC4; break;
        case hal::PixelFormat::kGray8: type = CV_8UC1; break;
        default: return false;
    }
    const cv::Mat src(in.format.height, in.format.width, type, in.data, in.format.stride);
    cv::Mat dst(out.format.height, out.format.width, type, out.data, out.format.stride);
    cv::remap(src, dst, impl_->map_xy, impl_->map_frac, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    return true;
}

}  // namespace endotower::calibration
