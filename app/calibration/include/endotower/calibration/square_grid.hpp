// The book's square-grid steps (ch. 2, figs. 2.7, 2.11, 2.12, tables 2.1-2.5): black
// squares on white at a known distance, perpendicular to the optical axis. Square
// centres are blob centroids (threshold, connected components) inside the field of
// view; the nine central squares give the centre-to-centre distances Dx, Dy, hence
// Sx/Sy = Dx/Dy (eq. 2.4) and f = D z / pitch (eq. 2.17); every square's offset from
// its ideal grid position gives the radial distortion samples (eq. 2.10).
#pragma once

#include <string>
#include <vector>

#include "endotower/calibration/field_of_view.hpp"
#include "endotower/calibration/gray_image.hpp"
#include "endotower/calibration/radial_polynomial.hpp"

namespace endotower::calibration {

// Centroids of the dark blobs inside `fov` (shrunk by 2%) whose area is within a
// factor 4 of the median blob. False with `error` naming the image when fewer than
// nine are found.
bool detect_square_centres(const GrayImage& image, const FovCircle& fov, std::vector<Point2>& out,
                           std::string& error);

// The 3x3 squares around the one nearest `centre`, as a lattice
//   p(i, j) = origin + i u + j v,  i, j in -1..1 (u along the image's x, v along y).
struct CentreSquares {
    Point2 origin, u, v;
    double dx = 0, dy = 0;     // |u|, |v|: centre-to-centre distances, px
    double sx_over_sy = 1;     // eq. 2.4: Dx / Dy
    double max_offset_px = 0;  // largest distance of the nine from the lattice
};
bool find_centre_squares(const std::vector<Point2>& centres, Point2 centre, CentreSquares& out,
                         std::string& error);

// Eq. 2.17 per axis: f = D z / pitch (px); and its use for depth, eq. 2.2: z = f pitch / D.
inline double focal_from_spacing(double d_px, double pitch_mm, double distance_mm) {
    return d_px * distance_mm / pitch_mm;
}
inline double distance_from_spacing(double d_px, double pitch_mm, double focal_px) {
    return focal_px * pitch_mm / d_px;
}

// Indexes every centre on the lattice (grown outwards from the centre squares, so
// strong barrel distortion at the rim does not confuse neighbours) and returns one
// sample per square: actual radius |p(i,j) - c| and dr = actual - measured radius.
// `measured` receives the matching measured centres (same order).
std::vector<RadialSample> radial_samples(const std::vector<Point2>& centres,
                                         const CentreSquares& grid, Point2 c,
                                         std::vector<Point2>* measured = nullptr,
                                         std::vector<Point2>* actual = nullptr);

// The radial fit of one chart image about the centre that minimises the book's total
// error: the real image centre is where the grid's lines stay straight, which the
// white-background circle centre (`start`) only approximates. Searched within
// `search_px` of `start` (1 px grid, then 0.05 px). False with `error` as
// fit_radial_polynomial, or when fewer than `order` + 1 squares were indexed.
struct BookDistortion {
    RadialFit fit;  // poly.cx, poly.cy: the centre found
    std::vector<RadialSample> samples;
    std::vector<Point2> measured, actual;  // per sample
};
bool fit_book_distortion(const std::vector<Point2>& centres, const CentreSquares& grid,
                         Point2 start, double search_px, int order, double r_max,
                         BookDistortion& out, std::string& error);

}  // namespace endotower::calibration
