// Sub-pixel centre of a dark blob found by connected components (internal).
#pragma once

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "endotower/calibration/gray_image.hpp"

namespace endotower::calibration {

// Darkness-weighted centroid over component `i`'s box grown by 2 px: the blurred,
// anti-aliased rim counts by how dark it is, so the centre is not quantised to the
// binary mask. Pixels of other components are skipped. `c` is left alone when the
// box has no contrast.
inline void refine_dark_centroid(const cv::Mat& gray, const cv::Mat& labels, const cv::Mat& stats,
                                 int i, Point2& c) {
    const int x0 = std::max(0, stats.at<int>(i, cv::CC_STAT_LEFT) - 2);
    const int y0 = std::max(0, stats.at<int>(i, cv::CC_STAT_TOP) - 2);
    const int x1 = std::min(
        gray.cols, stats.at<int>(i, cv::CC_STAT_LEFT) + stats.at<int>(i, cv::CC_STAT_WIDTH) + 2);
    const int y1 = std::min(
        gray.rows, stats.at<int>(i, cv::CC_STAT_TOP) + stats.at<int>(i, cv::CC_STAT_HEIGHT) + 2);
    int lo = 255, hi = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            lo = std::min<int>(lo, gray.at<std::uint8_t>(y, x));
            hi = std::max<int>(hi, gray.at<std::uint8_t>(y, x));
        }
    if (hi - lo <= 20) return;
    double sw = 0, sx = 0, sy = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const int l = labels.at<int>(y, x);
            if (l != 0 && l != i) continue;
            double w = (hi - gray.at<std::uint8_t>(y, x)) / static_cast<double>(hi - lo);
            w = w < 0.1 ? 0 : std::min(1.0, w);
            sw += w, sx += w * x, sy += w * y;
        }
    if (sw > 0) c = {sx / sw, sy / sw};
}

}  // namespace endotower::calibration
