// The book's whole procedure (ch. 2, ch. 3) over image sets, and the cross-checks
// that compare it with OpenCV's calibration:
//   1. white background -> field-of-view circle (mean over the images), fig. 2.6;
//   2. square chart at the reference distance -> Dx, Dy, Sx/Sy, fx = Dx z / pitch,
//      fy = Dy z / pitch (eq. 2.2-2.4, 2.17);
//   3. the chart image with the most squares -> odd radial polynomial of the chosen
//      order about the centre where the grid's lines stay straight (eq. 2.7-2.15);
//   4. every chart image with a known distance -> table 2.3 (z = f pitch / D);
//   5. two-dot marker images -> the separation table, with the pinhole cross-check.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "endotower/calibration/calibration_file.hpp"
#include "endotower/calibration/square_grid.hpp"
#include "endotower/calibration/target.hpp"

namespace endotower::calibration {

struct DistanceImage {
    GrayImage image;
    double distance_mm = 0;  // from the file name (e.g. 050mm.png); 0 = unknown
};

struct BookInputs {
    std::vector<GrayImage> white;
    std::vector<DistanceImage> chart;
    double pitch_mm = 8, reference_mm = 50;  // chart pitch; distance for the focal length
    int order = 3;
    std::vector<DistanceImage> marker;
    double marker_mm = 10;
};

struct BookResult {
    int width = 0, height = 0;  // of every image
    FovCircle fov;
    double fov_spread_px = 0;  // largest centre distance of one white image from the mean
    CentreSquares reference;   // the nine squares at the reference distance
    double fx = 0, fy = 0;
    BookDistortion distortion;
    std::string distortion_image;
    struct DistanceRow {
        std::string image;
        double actual_mm = 0, computed_mm = 0;
    };
    std::vector<DistanceRow> distances;  // table 2.3
    std::optional<SeparationTable> separation;
    std::vector<double> pinhole_px;  // per separation row: f marker / z
    double radial_rms_px() const;    // RMS of the polynomial's residuals
    // Model "book".
    Calibration calibration(const std::string& scope) const;
};

// False with `error` naming the image and what was missing: no white image, no
// circle, no chart image at the reference distance, grid not found, too few points,
// degenerate or non-monotonic fit, marker not found, images of different sizes.
bool run_book_calibration(const BookInputs& in, BookResult& out, std::string& error);

// Distance (eq. 2.2) of a chart image under an OpenCV camera: square centres
// undistorted with it, then z = fx pitch / Dx. False when the grid is not found.
bool opencv_chart_distance(const Calibration& camera, const GrayImage& chart, const FovCircle& fov,
                           double pitch_mm, double& z_mm, std::string& error);

// Reprojection RMS (px) of target views under the book's model: points corrected by
// the polynomial, each view's pose solved with fx, fy and the polynomial's centre,
// projected and distorted back.
double book_reprojection_rms(const std::vector<View>& views, const Calibration& book);

}  // namespace endotower::calibration
