// Undistorter: undistortion as one remap per frame. The maps are built once from a
// calibration (book: for every corrected pixel at radius r, the source at
// r - dr(r) on the same ray, the book's inverse mapping; pinhole/fisheye: OpenCV's
// undistortion maps with the same camera matrix) and stored as fixed-point maps
// (CV_16SC2 + 5-bit fractions) for a bilinear remap, applied in runs of pixels
// inside the field of view by our own loop: OpenCV's remap allocates per call.
// Corrected pixels whose source lies outside the field-of-view circle, or within one
// pixel of the frame's right or bottom edge, are black.
#pragma once

#include <memory>
#include <string>

#include "endotower/calibration/calibration_file.hpp"
#include "endotower/hal/frame.hpp"

namespace endotower::calibration {

class Undistorter {
public:
    Undistorter();
    ~Undistorter();
    Undistorter(Undistorter&&) noexcept;
    Undistorter& operator=(Undistorter&&) noexcept;

    // Builds the maps for frames of the calibration's image size. False with `error`
    // when the calibration cannot be inverted (e.g. a book polynomial that folds).
    bool init(const Calibration& c, std::string& error);
    // Remaps `in` into `out`: same size and format (bgr24, rgb24, bgra32 or gray8),
    // both buffers owned by the caller. Allocates nothing; false on a mismatch.
    // With two threads, the rows are split in halves of equal pixel count and a helper
    // thread (started once by set_threads) remaps one while the caller does the other.
    bool apply(const hal::Frame& in, hal::Frame& out) const;
    // 1 (default) or 2 threads for apply(); after init(). Not concurrent with apply().
    bool set_threads(int threads);
    int threads() const;
    // Where corrected pixel (x, y) samples the input (the exact map, before rounding).
    Point2 source_of(double x, double y) const;
    int width() const;
    int height() const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::calibration
