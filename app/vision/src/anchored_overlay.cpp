#include "endotower/vision/anchored_overlay.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>

namespace endotower::vision {

namespace {

struct Box {
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

Box marked_box(const RegionEstimate& e) {
    Box b{1e300, 1e300, -1e300, -1e300};
    for (std::size_t i = 0; i < e.vertices; ++i) {
        b.x0 = std::min(b.x0, e.marked[i].x), b.x1 = std::max(b.x1, e.marked[i].x);
        b.y0 = std::min(b.y0, e.marked[i].y), b.y1 = std::max(b.y1, e.marked[i].y);
    }
    return b;
}

cv::Matx33d homography_of(const RegionEstimate& e) {
    cv::Matx33d h;
    for (int i = 0; i < 9; ++i) h.val[i] = e.homography[static_cast<std::size_t>(i)];
    return h;
}

}  // namespace

std::string_view to_string(RegionOverlayKind k) {
    switch (k) {
        case RegionOverlayKind::kImage:
            return "image";
        case RegionOverlayKind::kObject:
            return "object";
        default:
            return "markers";
    }
}

bool parse_region_overlay(std::string_view text, RegionOverlay& out, std::string& error) {
    const std::string t(text);
    if (t == "markers") {
        out = {};
        return true;
    }
    if (t == "object:cube") {
        out = {RegionOverlayKind::kObject, {}};
        return true;
    }
    if (t.rfind("image:", 0) == 0) {
        const std::string path = t.substr(6);
        const std::filesystem::path p(path);
        if (path.empty()) {
            error = "overlay '" + t + "': image: needs a file in the media folder (image:PATH)";
            return false;
        }
        // Like the board's other media: inside the media folder, by a relative path.
        const std::filesystem::path norm = p.lexically_normal();
        if (p.is_absolute() || norm.empty() || *norm.begin() == "..") {
            error = "overlay '" + t + "': the image must be a relative path inside the media " +
                    "folder (sci.media), without leading '..'";
            return false;
        }
        out = {RegionOverlayKind::kImage, path};
        return true;
    }
    if (t.rfind("object:", 0) == 0) {
        error = "overlay '" + t + "': unknown object '" + t.substr(7) + "' (expected object:cube)";
        return false;
    }
    error = "overlay '" + t + "': expected markers, image:PATH or object:cube";
    return false;
}

bool anchored_image_corners(const RegionEstimate& e, int width, int height,
                            std::array<Point2, 4>& out) {
    if (e.vertices < 3 || width <= 0 || height <= 0) return false;
    const Box b = marked_box(e);
    const double scale = std::min((b.x1 - b.x0) / width, (b.y1 - b.y0) / height);
    const double w = width * scale, h = height * scale;
    const double left = b.x0 + (b.x1 - b.x0 - w) / 2, top = b.y0 + (b.y1 - b.y0 - h) / 2;
    const double xs[4] = {left, left + w, left + w, left};
    const double ys[4] = {top, top, top + h, top + h};
    const cv::Matx33d hm = homography_of(e);
    for (int k = 0; k < 4; ++k) {
        const cv::Vec3d p = hm * cv::Vec3d(xs[k], ys[k], 1);
        if (!(p[2] > 1e-9)) return false;
        out[static_cast<std::size_t>(k)] = {p[0] / p[2], p[1] / p[2]};
    }
    return true;
}

bool tissue_pose(const RegionEstimate& e, const hal::SceneCamera& camera, double depth_mm,
                 TissuePose& out) {
    out.valid = false;
    if (!camera.valid() || e.vertices < 3 || !(depth_mm > 0)) return false;
    const Box b = marked_box(e);
    const double uc = (b.x0 + b.x1) / 2, vc = (b.y0 + b.y1) / 2;
    // Plane millimetres (origin at the box's centre) -> marking-frame pixels.
    const cv::Matx33d m(camera.fx / depth_mm, 0, uc, 0, camera.fy / depth_mm, vc, 0, 0, 1);
    const cv::Matx33d k_inv =
        cv::Matx33d(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1).inv();
    const cv::Matx33d a = k_inv * homography_of(e) * m;
    cv::Vec3d a1(a(0, 0), a(1, 0), a(2, 0)), a2(a(0, 1), a(1, 1), a(2, 1)),
        a3(a(0, 2), a(1, 2), a(2, 2));
    const double n1 = cv::norm(a1), n2 = cv::norm(a2);
    if (!(n1 > 1e-12 && n2 > 1e-12)) return false;
    double s = 2 / (n1 + n2);
    if (a3[2] < 0) s = -s;  // the tissue is in front of the camera
    const cv::Vec3d r1 = a1 * s, r2 = a2 * s, t = a3 * s;
    // The nearest rotation to [r1 r2 r1 x r2] (noise makes r1, r2 not quite orthonormal).
    // Fixed-size Eigen: no allocation (cv::SVD allocates; this runs every frame).
    const cv::Vec3d r3 = r1.cross(r2);
    Eigen::Matrix3d r;
    r << r1[0], r2[0], r3[0], r1[1], r2[1], r3[1], r1[2], r2[2], r3[2];
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d rot = svd.matrixU() * svd.matrixV().transpose();
    if (rot.determinant() < 0 || !(t[2] > 0)) return false;
    for (int i = 0; i < 9; ++i) out.rotation[static_cast<std::size_t>(i)] = rot(i / 3, i % 3);
    out.origin_mm = {t[0], t[1], t[2]};
    out.width_mm = (b.x1 - b.x0) / camera.fx * depth_mm;
    out.height_mm = (b.y1 - b.y0) / camera.fy * depth_mm;
    out.valid = true;
    return true;
}

hal::SceneBox anchored_cube(const TissuePose& pose, const std::array<hal::Rgba8, 6>& faces) {
    hal::SceneBox box;
    const double edge = std::min(pose.width_mm, pose.height_mm) / 2;
    box.size_mm = static_cast<float>(edge);
    box.faces = faces;
    const auto& r = pose.rotation;
    // Standing on the tissue: the centre half an edge out of the plane, towards the
    // camera (the plane's -z).
    const double c[3] = {pose.origin_mm.x - r[2] * edge / 2, pose.origin_mm.y - r[5] * edge / 2,
                         pose.origin_mm.z - r[8] * edge / 2};
    for (int col = 0; col < 3; ++col)
        for (int row = 0; row < 3; ++row)
            box.camera_from_model[4 * static_cast<std::size_t>(col) +
                                  static_cast<std::size_t>(row)] =
                static_cast<float>(
                    r[3 * static_cast<std::size_t>(row) + static_cast<std::size_t>(col)]);
    box.camera_from_model[12] = static_cast<float>(c[0]);
    box.camera_from_model[13] = static_cast<float>(c[1]);
    box.camera_from_model[14] = static_cast<float>(c[2]);
    box.camera_from_model[15] = 1;
    return box;
}

}  // namespace endotower::vision
