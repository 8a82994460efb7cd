// ToolPose: the 3-D pose of a cylindrical tool from its two image edges, its tip and
// its known diameter, with a calibrated camera (book ch. 4, eq. 4.22-4.27, after
// Cano et al. 2006).
//
// Inputs: the pinhole intrinsics of the undistorted image; the two silhouette edges,
// each as two points (undistorted px); the tip (undistorted px); a point of the shaft
// towards the incision (e.g. where the midline leaves the field of view), which only
// orients the axis; the shaft diameter in mm.
// Outputs (camera frame, mm: x right, y down, z forward):
//   tip_mm     the tip P: the back-projected tip ray meeting the plane that holds the
//              axis and is perpendicular to CN (eq. 4.26);
//   axis_mm    N, the point of the axis nearest the camera centre (eq. 4.24, 4.25);
//   axis_dir   unit vector of the shaft from the tip towards the incision;
//   yaw_deg    left-right rotation of the shaft, atan2(t.x, t.z) of the direction t
//              from the incision to the tip; pitch_deg = atan2(-t.y, |t.xz|);
//   depth_sigma_mm  the 1-px sensitivity of |CN| (how far a one-pixel error in the
//              apparent width moves the tool); confidence = 1 / (1 + depth_sigma_mm).
// Roll about the shaft cannot be observed from the edges (the book says so too).
#pragma once

namespace endotower::vision {

struct Point2 {
    double x = 0, y = 0;
};
struct Vec3 {
    double x = 0, y = 0, z = 0;
};
struct PinholeCamera {
    double fx = 0, fy = 0, cx = 0, cy = 0;
};
struct EdgeLine {
    Point2 a, b;  // two distinct points on the edge
};

struct ToolPose {
    bool valid = false;  // false: edges parallel in 3-D space through C, or P behind C
    Vec3 tip_mm, axis_mm, axis_dir;
    double distance_to_axis_mm = 0;  // |CN|
    double yaw_deg = 0, pitch_deg = 0;
    double depth_sigma_mm = 0;
    double confidence = 0;
};

ToolPose reconstruct_tool_pose(const PinholeCamera& camera, const EdgeLine& e1, const EdgeLine& e2,
                               Point2 tip_px, Point2 toward_incision_px, double diameter_mm);

}  // namespace endotower::vision
