// The reduction of a BGR24 frame to an analysis image, shared by the analysis stages
// (likelihood tracker, gesture segmenter, the book's trackers): `small` keeps the size
// its stage gave it in configure(). Where `reduce` was configured for this frame's
// size, AreaMean (cv::resize's INTER_AREA bytes without its per-call allocation); a
// frame of the analysis size is copied; any other size goes through cv::resize
// (allocating: a frame whose size changed mid-stream until the stage is configured
// again). Private to app/vision.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "endotower/hal/frame.hpp"
#include "endotower/vision/area_mean.hpp"

namespace endotower::vision::detail {

inline void reduce_frame(const hal::Frame& frame, AreaMean& reduce, cv::Mat& small) {
    if (reduce.fits(frame.format.width, frame.format.height)) {
        reduce.run(frame.data, frame.format.stride, small.data, small.step);
        return;
    }
    const cv::Mat full(frame.format.height, frame.format.width, CV_8UC3, frame.data,
                       frame.format.stride);
    if (full.size() == small.size())
        full.copyTo(small);
    else
        cv::resize(full, small, small.size(), 0, 0, cv::INTER_AREA);
}

}  // namespace endotower::vision::detail
