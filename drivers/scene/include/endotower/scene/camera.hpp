// The endoscope camera: pinhole intrinsics with an off-centre principal point and
// unequal scale factors (fx = f Sx, fy = f Sy, book ch. 2), the book's odd radial
// polynomial barrel distortion about (cx, cy), and a circular field of view with
// vignetting.
//
// Distortion (docs/truth.md): a point at undistorted radius r_u (px from (cx, cy)) is
// displayed at r_d = r_u (1 + k1 r_u^2 + k2 r_u^4 + ...), same polar angle.
// undistort() inverts it by Newton's method; it fails past the radius where r_d
// stops growing (the model has no inverse there), which lies outside the field of view
// for the default lenses.
//
// CameraSpec holds the lens in size-independent units (fractions of the image height),
// so one scenario renders at 640x480 and 1920x1080 alike; make_camera() turns it into
// pixels for one output size.
#pragma once

#include <vector>

#include "endotower/scene/vec.hpp"

namespace endotower::scene {

struct CameraSpec {
    double focal = 0.868;               // fx / height (416.7 px at 480 rows, book eq. 2.17)
    double sy_over_sx = 65.83 / 66.67;  // fy / fx (book: Sx/Sy = 66.67/65.83)
    double center_offset[2] = {0.0125, -0.0083};  // (cx, cy) - sensor centre, / height
    std::vector<double> k = {-0.32, 0.06};        // k_i for r measured in image heights
    double fov_radius = 0.49;                     // illuminated circle radius / height
    double vignetting = 0.45;                     // brightness lost at the field-of-view rim
    double blur_px = 0.35;                        // optical blur sigma / (height / 480)
};

struct CameraModel {
    int width = 640, height = 480;
    double fx = 0, fy = 0, cx = 0, cy = 0;
    std::vector<double> k;  // per px^(2i), as in truth.jsonl
    double fov_cx = 0, fov_cy = 0, fov_radius = 0;
    double vignetting = 0, blur_sigma = 0;

    // Undistorted <-> displayed pixel coordinates.
    void distort(double xu, double yu, double& xd, double& yd) const;
    bool undistort(double xd, double yd, double& xu, double& yu) const;
    // Camera-frame point (mm) -> undistorted / displayed pixel; false if z <= 0.
    bool project_undistorted(Vec3 p, double& xu, double& yu) const;
    bool project(Vec3 p, double& xd, double& yd) const;
    // Ray direction (not normalised, z = 1) through an undistorted pixel.
    Vec3 ray(double xu, double yu) const { return {(xu - cx) / fx, (yu - cy) / fy, 1.0}; }
    bool in_fov(double xd, double yd) const;
    // Largest undistorted radius where the distortion is still monotonic.
    double max_undistorted_radius() const;
};

CameraModel make_camera(const CameraSpec& spec, int width, int height);

}  // namespace endotower::scene
