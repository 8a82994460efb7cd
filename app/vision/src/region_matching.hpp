// Region matching internals (book ch. 6): feature detection in a window of a grey
// frame at a bounded working width, and keyframe-to-frame matching with the book's
// filters and a RANSAC homography. Private to endotower_vision (OpenCV types).
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

#include "endotower/vision/region_tracker.hpp"

namespace endotower::vision::detail {

// Keypoints in the full frame's pixels, descriptors one row each.
struct FeatureSet {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    void clear() {
        keypoints.clear();
        descriptors.release();
    }
};

class FeatureDetector {
public:
    // max_features 0 = all (SIFT, AKAZE); ORB needs a number.
    FeatureDetector(RegionDescriptor d, int max_width, int max_features);
    // Detects in `roi` of `gray` (mask: roi-sized, or empty), downscaled when gray is
    // wider than max_width; keypoints come back in gray's pixels.
    void detect(const cv::Mat& gray, cv::Rect roi, const cv::Mat& mask, FeatureSet& out);
    int norm() const { return norm_; }
    // Input pixels per working pixel for a frame this wide (>= 1).
    double pixel_size(int frame_width) const;

private:
    cv::Ptr<cv::Feature2D> feature_;
    int norm_ = cv::NORM_L2;
    int max_width_;
    int max_features_;
    bool cap_after_detection_ = false;
    cv::Mat small_, small_mask_;
};

struct MatchParams {
    double ratio = 0.8;
    double ransac_px = 3.0;  // in input pixels
    int min_inliers = 10;
};

struct KeyframeMatch {
    cv::Matx33d homography = cv::Matx33d::eye();  // keyframe pixels -> frame pixels
    int inliers = 0;
    std::vector<cv::Point2f> keyframe_pts, frame_pts;  // the inlier pairs
};

// Brute-force 2-NN matching (norm L2 or Hamming), Lowe's ratio test, then the book's
// "well-matched pairs": distance below the average of the surviving matches; RANSAC
// homography. False when fewer than min_inliers pairs survive.
bool match_keyframe(const FeatureSet& keyframe, const FeatureSet& frame, int norm,
                    const MatchParams& p, KeyframeMatch& out);

}  // namespace endotower::vision::detail
