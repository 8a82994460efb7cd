// The endoscope's field of view (book fig. 2.6): pointed at a white background, the
// scope shows an illuminated circle; its centre is the book's real image centre and
// the circle is the mask every later step uses (nothing is detected outside it).
#pragma once

#include <string>
#include <vector>

#include "endotower/calibration/gray_image.hpp"

namespace endotower::calibration {

struct FovCircle {
    double cx = 0, cy = 0, radius = 0;  // px, in the image the circle was found in
    bool valid() const { return radius > 0; }
    // True if (x, y) lies inside the circle shrunk by `margin` px.
    bool contains(double x, double y, double margin = 0) const;
};

// Finds the illuminated circle in `image`: threshold between the dark surround and
// the lit disc, largest component, convex hull (dark tissue at the rim does not cut
// into it), least-squares circle through the hull points off the image border; then
// refined on the rim's local mid level along 64 rays (FovMonitor's measurement).
// False with `error` naming the image when there is no bright disc, the disc is too
// small (< 5% of the image) or its outline is not a circle (fit residual > 2% of
// the radius, or the disc fills < 80% of its circle).
bool detect_fov_circle(const GrayImage& image, FovCircle& out, std::string& error);

// Least-squares (algebraic, Kasa) circle through points xs[i], ys[i]; returns the RMS
// distance of the points from the circle, or a negative value with < 3 points or
// collinear points.
double fit_circle(const double* xs, const double* ys, int n, FovCircle& out);

}  // namespace endotower::calibration
