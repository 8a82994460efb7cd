// A deterministic tissue-like texture for the region tests: smoothed random blobs at
// several scales and dark vessel-like strokes, BGR.
#pragma once

#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace endotower::vision::test {

inline cv::Mat texture(int w, int h, std::uint64_t seed) {
    cv::RNG rng(seed);
    cv::Mat acc(h, w, CV_32F, cv::Scalar(0));
    for (int cell : {4, 9, 20, 50}) {
        cv::Mat small(h / cell + 2, w / cell + 2, CV_32F), big;
        rng.fill(small, cv::RNG::UNIFORM, 0, 1);
        cv::resize(small, big, cv::Size(w, h), 0, 0, cv::INTER_CUBIC);
        acc += big * std::sqrt(cell / 20.0);
    }
    // Vessel-like dark curves.
    for (int i = 0; i < w * h / 8000; ++i) {
        const cv::Point a(rng.uniform(0, w), rng.uniform(0, h));
        const cv::Point b = a + cv::Point(rng.uniform(-60, 60), rng.uniform(-60, 60));
        cv::line(acc, a, b, cv::Scalar(-0.8), rng.uniform(1, 4), cv::LINE_AA);
    }
    cv::Mat u8, bgr;
    cv::normalize(acc, acc, 30, 230, cv::NORM_MINMAX);
    acc.convertTo(u8, CV_8U);
    cv::cvtColor(u8, bgr, cv::COLOR_GRAY2BGR);
    return bgr;
}

}  // namespace endotower::vision::test
