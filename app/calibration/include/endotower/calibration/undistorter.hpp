// Undistorter: undistortion as one remap per frame. The map is built once from a
// calibration (book: for every corrected pixel at radius r, the source at
// r - dr(r) on the same ray, the book's inverse mapping; pinhole/fisheye: OpenCV's
// undistortion maps with the same camera matrix) and stored every 8th pixel of each
// row in fixed point (4th, 2nd or every pixel where needed for the 0.05 px below);
// the pixels between are linear in x, expanded per run into
// OpenCV's fixed-point layout (CV_16SC2 + 5-bit fractions) for a bilinear remap by our
// own loop (OpenCV's remap allocates per call). Streaming 1 byte of map per pixel
// instead of 6 is what makes the 1080p remap fit in 3 ms; the interpolation error is
// checked per pixel at init (map_stats). Corrected pixels whose source lies outside
// the field-of-view circle, or within one pixel of the frame's right or bottom edge,
// are black.
#pragma once

#include <cstddef>
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
    // False for another count, or when no thread can be started (apply() stays on one).
    bool set_threads(int threads);
    int threads() const;
    // The pixel loop: kBest picks the widest this CPU runs (AVX2, else SSE2 on x86-64;
    // the portable loop elsewhere). All give the same bytes; forcing one is for tests
    // and benchmarks. False when this CPU or build lacks it.
    enum class Kernel { kBest, kScalar, kSse2, kAvx2 };
    bool set_kernel(Kernel k);
    Kernel kernel() const;
    // Where corrected pixel (x, y) samples the input (the exact map, before rounding).
    Point2 source_of(double x, double y) const;
    // The stored map against the exact one: node spacing (px), the largest error on a
    // remapped pixel (px, <= 0.05, rounding to 1/32 px included), remapped pixels.
    struct MapStats {
        int node_step = 0;
        double max_error_px = 0;
        std::size_t remapped = 0;
    };
    MapStats map_stats() const;
    int width() const;
    int height() const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::calibration
