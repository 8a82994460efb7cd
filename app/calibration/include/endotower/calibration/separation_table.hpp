// Depth and pixel-to-millimetre conversion (book ch. 3, figs. 3.3-3.5, eq. 3.1-3.2):
// a marker with two dots `marker_mm` (10) apart, imaged at known distances, gives the
// on-screen separation per distance. Between recorded distances the separation is
// interpolated linearly (the book's 74 mm example: 50 + (40 - 50)(74 - 70)/(80 - 70)
// = 46 px, i.e. 1 mm : 4.6 px). The pinhole relation sep = f marker / z from the
// focal length (eq. 2.2) is the cross-check.
#pragma once

#include <string>
#include <vector>

#include "endotower/calibration/field_of_view.hpp"
#include "endotower/calibration/gray_image.hpp"

namespace endotower::calibration {

class SeparationTable {
public:
    double marker_mm = 10.0;
    std::vector<double> distances_mm;   // strictly increasing
    std::vector<double> separation_px;  // strictly decreasing (farther = smaller)

    // False with `error` when the table is not usable: fewer than two rows, lengths
    // differ, distances not increasing or separations not decreasing.
    bool validate(std::string& error) const;
    // Separation at depth z (linear between rows; the end segments extrapolate).
    double separation_at(double z_mm) const;
    // px per mm at depth z (the book's conversion factor "1 mm : N px").
    double px_per_mm(double z_mm) const { return separation_at(z_mm) / marker_mm; }
    // Eq. 3.1/3.2: millimetres from the camera axis of a pixel coordinate at depth z.
    double to_mm(double pixel, double offset_px, double z_mm) const {
        return (pixel - offset_px) / px_per_mm(z_mm);
    }
    // Depth at which the marker shows `separation` px (the inverse interpolation).
    double depth_for_separation(double separation) const;
};

// Centres of the two dots: the two largest dark, compact blobs inside `fov`. False
// with `error` naming the image when two dots are not found.
bool detect_two_dots(const GrayImage& image, const FovCircle& fov, Point2& a, Point2& b,
                     std::string& error);

// Pinhole separation for the cross-check: f marker / z.
inline double pinhole_separation(double focal_px, double marker_mm, double z_mm) {
    return focal_px * marker_mm / z_mm;
}

}  // namespace endotower::calibration
