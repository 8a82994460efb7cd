// Synthetic endoscope frames with exact ground truth for the book's trackers: a
// textured red tissue (fixed texture, fresh sensor noise per frame) and a dark
// shaft entering from the image border; and heap counters.
#pragma once

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "endotower/vision/tool_tracker.hpp"
#include "heap_counter.hpp"

namespace endotower::vision::test {

struct ShaftTruth {
    Point2 entry, tip;
    double width = 0;
    double axis_deg() const { return std::atan2(entry.y - tip.y, entry.x - tip.x) * 180.0 / M_PI; }
};

inline cv::Mat tissue(int w, int h) {
    cv::Mat img(h, w, CV_8UC3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double v =
                18 * std::sin(x * 0.021 + 0.3 * std::sin(y * 0.017)) * std::cos(y * 0.013);
            img.at<cv::Vec3b>(y, x) =
                cv::Vec3b(cv::saturate_cast<uchar>(85 + v), cv::saturate_cast<uchar>(75 + v),
                          cv::saturate_cast<uchar>(185 + v));
        }
    return img;
}

// Tissue + noise (seeded by `t`) + the shaft (if truth.width > 0) into `out`.
inline void compose(const cv::Mat& background, const ShaftTruth& truth, int t, cv::Mat& out) {
    out.create(background.size(), CV_8UC3);
    cv::theRNG().state = static_cast<std::uint64_t>(t) * 7919 + 17;
    cv::randn(out, cv::Scalar(0, 0, 0), cv::Scalar(4, 4, 4));
    cv::add(background, out, out);
    if (truth.width <= 0) return;
    // A flat-ended shaft: the tip is exactly the end of its midline.
    const double l = std::hypot(truth.tip.x - truth.entry.x, truth.tip.y - truth.entry.y);
    const double nx = -(truth.tip.y - truth.entry.y) / l * truth.width / 2;
    const double ny = (truth.tip.x - truth.entry.x) / l * truth.width / 2;
    const cv::Point pts[4] = {cv::Point(cvRound(truth.entry.x + nx), cvRound(truth.entry.y + ny)),
                              cv::Point(cvRound(truth.tip.x + nx), cvRound(truth.tip.y + ny)),
                              cv::Point(cvRound(truth.tip.x - nx), cvRound(truth.tip.y - ny)),
                              cv::Point(cvRound(truth.entry.x - nx), cvRound(truth.entry.y - ny))};
    cv::fillConvexPoly(out, pts, 4, cv::Scalar(52, 50, 54), cv::LINE_AA);
}

inline hal::Frame frame_of(cv::Mat& img) {
    hal::Frame f;
    f.format = {img.cols, img.rows, static_cast<int>(img.step), hal::PixelFormat::kBgr24};
    f.data = img.data;
    return f;
}

inline double tip_error(const ToolEstimate& e, const ShaftTruth& t) {
    return std::hypot(e.tip.x - t.tip.x, e.tip.y - t.tip.y);
}

inline double axis_error_deg(const ToolEstimate& e, const ShaftTruth& t) {
    return std::abs(std::remainder(e.axis_deg - t.axis_deg(), 360.0));
}

}  // namespace endotower::vision::test
