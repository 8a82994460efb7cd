#include "region_matching.hpp"

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace endotower::vision::detail {

FeatureDetector::FeatureDetector(RegionDescriptor d, int max_width, int max_features)
    : max_width_(std::max(64, max_width)), max_features_(max_features) {
    switch (d) {
        case RegionDescriptor::kSift:
            // Table 6.1: octaves from the image size, the levels per octave OpenCV's 3
            // (the book's "four levels" counts the extra DoG level); a contrast
            // threshold of 0.01 instead of 0.04: tissue is low in contrast.
            feature_ = cv::SIFT::create(max_features, 3, 0.01);
            norm_ = cv::NORM_L2;
            break;
        case RegionDescriptor::kOrb:
            // Table 6.1: Harris score; 500 features in the book, more for whole frames.
            // A low FAST threshold (5): tissue is low in contrast.
            feature_ = cv::ORB::create(max_features > 0 ? max_features : 500, 1.2f, 8, 15, 0, 2,
                                       cv::ORB::HARRIS_SCORE, 15, 5);
            norm_ = cv::NORM_HAMMING;
            break;
        case RegionDescriptor::kAkaze:
            // A tenth of the default threshold: tissue is low in contrast.
            feature_ = cv::AKAZE::create(cv::AKAZE::DESCRIPTOR_MLDB, 0, 3, 0.0001f);
            cap_after_detection_ = max_features > 0;  // AKAZE has no feature budget of its own
            norm_ = cv::NORM_HAMMING;
            break;
    }
}

double FeatureDetector::pixel_size(int frame_width) const {
    return frame_width > max_width_ ? static_cast<double>(frame_width) / max_width_ : 1.0;
}

void FeatureDetector::detect(const cv::Mat& gray, cv::Rect roi, const cv::Mat& mask,
                             FeatureSet& out) {
    out.clear();
    roi &= cv::Rect(0, 0, gray.cols, gray.rows);
    if (roi.width < 16 || roi.height < 16) return;
    const double px = pixel_size(gray.cols);
    const cv::Mat window = gray(roi);
    cv::Mat work = window, work_mask = mask;
    if (px > 1.0) {
        const cv::Size s(std::max(1, static_cast<int>(roi.width / px)),
                         std::max(1, static_cast<int>(roi.height / px)));
        cv::resize(window, small_, s, 0, 0, cv::INTER_AREA);
        work = small_;
        if (!mask.empty()) {
            cv::resize(mask, small_mask_, s, 0, 0, cv::INTER_NEAREST);
            work_mask = small_mask_;
        }
    }
    if (cap_after_detection_) {
        feature_->detect(work, out.keypoints, work_mask);
        cv::KeyPointsFilter::retainBest(out.keypoints, max_features_);
        feature_->compute(work, out.keypoints, out.descriptors);
    } else {
        feature_->detectAndCompute(work, work_mask, out.keypoints, out.descriptors);
    }
    const double sx = static_cast<double>(roi.width) / work.cols,
                 sy = static_cast<double>(roi.height) / work.rows;
    for (cv::KeyPoint& k : out.keypoints) {
        // Pixel centres: working pixel (i + 0.5) covers input pixels up to (i + 1) * s.
        k.pt.x = static_cast<float>((k.pt.x + 0.5) * sx - 0.5 + roi.x);
        k.pt.y = static_cast<float>((k.pt.y + 0.5) * sy - 0.5 + roi.y);
        k.size = static_cast<float>(k.size * sx);
    }
}

bool match_keyframe(const FeatureSet& keyframe, const FeatureSet& frame, int norm,
                    const MatchParams& p, KeyframeMatch& out) {
    out.inliers = 0;
    out.keyframe_pts.clear();
    out.frame_pts.clear();
    if (keyframe.keypoints.size() < 4 || frame.keypoints.size() < 2) return false;
    cv::BFMatcher matcher(norm);
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(keyframe.descriptors, frame.descriptors, knn, 2);
    std::vector<cv::DMatch> kept;
    kept.reserve(knn.size());
    double sum = 0;
    for (const auto& m : knn) {
        if (m.size() < 2 || m[0].distance >= p.ratio * m[1].distance) continue;
        kept.push_back(m[0]);
        sum += m[0].distance;
    }
    if (kept.size() < static_cast<std::size_t>(std::max(4, p.min_inliers))) return false;
    // The book's well-matched pairs: shorter than the average distance. Ties (Hamming
    // distances are integers) stay, so a set of equal distances is not emptied.
    const double mean = sum / static_cast<double>(kept.size());
    std::size_t below = 0;
    for (const cv::DMatch& m : kept) below += m.distance <= mean;
    // A small region has few matches: when the filter would leave too few for
    // RANSAC to be meaningful, RANSAC sorts the ratio-tested set instead.
    const bool filter = below >= 2 * static_cast<std::size_t>(p.min_inliers);
    for (const cv::DMatch& m : kept) {
        if (filter && m.distance > mean) continue;
        out.keyframe_pts.push_back(keyframe.keypoints[m.queryIdx].pt);
        out.frame_pts.push_back(frame.keypoints[m.trainIdx].pt);
    }
    if (out.keyframe_pts.size() < static_cast<std::size_t>(std::max(4, p.min_inliers)))
        return false;
    std::vector<std::uint8_t> inlier_mask;
    const cv::Mat h = cv::findHomography(out.keyframe_pts, out.frame_pts, cv::RANSAC, p.ransac_px,
                                         inlier_mask, 2000, 0.995);
    if (h.empty()) return false;
    std::size_t n = 0;
    for (std::size_t i = 0; i < inlier_mask.size(); ++i) {
        if (!inlier_mask[i]) continue;
        out.keyframe_pts[n] = out.keyframe_pts[i];
        out.frame_pts[n] = out.frame_pts[i];
        ++n;
    }
    out.keyframe_pts.resize(n);
    out.frame_pts.resize(n);
    out.inliers = static_cast<int>(n);
    out.homography = cv::Matx33d(h);
    return out.inliers >= p.min_inliers;
}

}  // namespace endotower::vision::detail
