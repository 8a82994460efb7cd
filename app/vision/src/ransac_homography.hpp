// RansacHomography: a homography from point pairs with outliers (book eq. 6.4), for the
// region's per-frame propagation, allocation-free once reserved. Hand-written because
// cv::findHomography(RANSAC) allocates on every call (96 heap allocations for 150 pairs
// on OpenCV 4.6, measured with the allocation counter; docs/regions.md).
//
// Method: Hartley normalisation of both point sets; RANSAC over 4-pair samples, each
// solved by the 4-point DLT (h33 = 1, an 8x8 Eigen fixed-size system), samples with
// three nearly collinear points or a flipped orientation refused; an adaptive number of
// iterations for `confidence` (as OpenCV's); the best sample's inliers refitted by
// least squares (DLT over all of them, then Levenberg-Marquardt on the reprojection
// error), and the inliers taken again from the refitted homography.
// Deterministic: the random generator is seeded from `seed` on every call, so the same
// input gives the same result. No exceptions and no allocation: the inliers are counted
// and refitted in passes over the pairs, without buffers.
// Refused (false, the homography and mask untouched beyond their size): fewer than 4
// pairs, sizes that differ, non-finite coordinates, no sample that is not degenerate
// (e.g. all points collinear), or fewer than 4 inliers / a singular or non-finite fit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core/types.hpp>
#include <span>

namespace endotower::vision::detail {

struct RansacParams {
    double threshold_px = 3.0;  // inlier: reprojection distance in `to` at most this
    int max_iterations = 500;
    double confidence = 0.995;
    std::uint64_t seed = 0x5eed'cafe'f00d'1234ULL;
    int refine_iterations = 10;  // Levenberg-Marquardt steps of the refit
};

class RansacHomography {
public:
    explicit RansacHomography(RansacParams p = {}) : p_(p) {}
    const RansacParams& params() const { return p_; }
    void set_threshold(double px) { p_.threshold_px = px; }
    // Fits h (row-major, from -> to, h33 = 1) to the pairs; inliers[i] = 1 for the pairs
    // within the threshold of h, else 0. inliers.size() must equal from.size().
    bool fit(std::span<const cv::Point2f> from, std::span<const cv::Point2f> to, cv::Matx33d& h,
             std::span<std::uint8_t> inliers);
    int inlier_count() const { return inlier_count_; }  // of the last successful fit
    int iterations() const { return iterations_; }      // samples drawn by the last fit

private:
    RansacParams p_;
    int inlier_count_ = 0;
    int iterations_ = 0;
};

}  // namespace endotower::vision::detail
