#include "endotower/vision/tool_pose.hpp"

#include <Eigen/Dense>
#include <cmath>

namespace endotower::vision {

namespace {

using Eigen::Vector3d;

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// Direction of the ray from the camera centre C through pixel p.
Vector3d ray(const PinholeCamera& k, Point2 p) {
    return Vector3d((p.x - k.cx) / k.fx, (p.y - k.cy) / k.fy, 1.0).normalized();
}

Vec3 to_vec(const Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

ToolPose reconstruct_tool_pose(const PinholeCamera& camera, const EdgeLine& e1, const EdgeLine& e2,
                               Point2 tip_px, Point2 toward_incision_px, double diameter_mm) {
    ToolPose pose;
    if (camera.fx <= 0 || camera.fy <= 0 || diameter_mm <= 0) return pose;

    // Eq. 4.22: the normal of each tangent plane Omega_i, which holds C and edge E_i.
    Vector3d n1 = ray(camera, e1.a).cross(ray(camera, e1.b));
    Vector3d n2 = ray(camera, e2.a).cross(ray(camera, e2.b));
    if (n1.norm() < 1e-12 || n2.norm() < 1e-12) return pose;
    n1.normalize();
    n2.normalize();
    // Both normals must point to the tool's side of their plane: the ray through the
    // middle of the silhouette lies inside the wedge the two planes form.
    const Point2 mid{(e1.a.x + e1.b.x + e2.a.x + e2.b.x) / 4, (e1.a.y + e1.b.y + e2.a.y + e2.b.y) / 4};
    const Vector3d inside = ray(camera, mid);
    if (n1.dot(inside) < 0) n1 = -n1;
    if (n2.dot(inside) < 0) n2 = -n2;

    const Vector3d sum = n1 + n2, diff = n1 - n2;
    if (sum.norm() < 1e-12) return pose;  // planes coincide: no width seen
    // Eq. 4.23: half the angle the tool subtends at C, lambda_N.
    const double lambda = std::atan2(sum.norm(), diff.norm());
    if (!(lambda > 1e-9 && lambda < 1.5707)) return pose;
    const double radius = 0.5 * diameter_mm;
    // Eq. 4.24, 4.25: the axis point nearest C.
    const double cn = radius / std::sin(lambda);
    const Vector3d u_cn = sum.normalized();
    const Vector3d n = cn * u_cn;
    // Eq. 4.26: the tip ray meets the plane through the axis perpendicular to CN.
    const Vector3d u_ct = ray(camera, tip_px);
    const double along = u_ct.dot(u_cn);
    if (along <= 1e-9) return pose;
    const Vector3d p = (cn / along) * u_ct;
    if (p.z() <= 0) return pose;

    // The axis is parallel to both tangent planes. Eq. 4.27 gives NP along it; its
    // sign is taken from the point towards the incision (NP itself vanishes when the
    // tip projects onto N).
    Vector3d axis = n1.cross(n2);
    if (axis.norm() < 1e-12) return pose;
    axis.normalize();
    const Vector3d u_far = ray(camera, toward_incision_px);
    const Vector3d far = (cn / std::max(u_far.dot(u_cn), 1e-9)) * u_far;
    if ((far - p).dot(axis) < 0) axis = -axis;

    const Vector3d t = -axis;  // incision -> tip
    pose.valid = true;
    pose.tip_mm = to_vec(p);
    pose.axis_mm = to_vec(n);
    pose.axis_dir = to_vec(axis);
    pose.distance_to_axis_mm = cn;
    pose.yaw_deg = std::atan2(t.x(), t.z()) * kRadToDeg;
    pose.pitch_deg = std::atan2(-t.y(), std::hypot(t.x(), t.z())) * kRadToDeg;
    // Apparent width w ~ 2 f tan(lambda); |CN| ~ 1 / w, so one pixel of width moves
    // |CN| by about |CN| / w.
    const double f = 0.5 * (camera.fx + camera.fy);
    pose.depth_sigma_mm = cn / (2.0 * f * std::tan(lambda));
    pose.confidence = 1.0 / (1.0 + pose.depth_sigma_mm);
    return pose;
}

}  // namespace endotower::vision
