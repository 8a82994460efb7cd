// GestureFeatures: the six shape features of the book's tool-gesture classifier
// (ch. 3, figs. 3.15-3.20), measured on one binary blob.
//
// Input: an 8-bit mask (nonzero = blob), width x height, `stride` bytes per row,
// borrowed for the call. The blob is the largest outer contour of the mask
// (OpenCV's border following, ContourTracer: a polygon through the boundary pixels'
// centres).
// Outputs, with P = that polygon's perimeter, A = its area, H = its convex hull:
//   compactness        P^2 / (4 pi A): 1 for a disc, larger when convoluted;
//   roughness          P / perimeter(H): 1 for a convex blob;
//   elongation         length / breadth with length x breadth = A and
//                      2 (length + breadth) = P (1 when no real solution);
//   feret_elongation   max Feret diameter (the hull's diameter) / min Feret
//                      diameter (the hull's width over its edge directions: exact);
//   max_changes, min_changes
//                      the most and fewest 0<->1 changes along `kScanLines` (10)
//                      lines through the mask's centroid 18 degrees apart (fig. 3.19),
//                      each crossing the whole mask (outside counts as 0).
// A mask without a blob of at least 3 pixels gives valid = false.
// The extra features of the improved classifier (as_vector(kExtended)): the fill
// ratio A / area(H), the first Hu moment invariant and the square root of the
// second (same units). The topology features (kTopology: the nine and these two):
// hole1, hole2 = the two largest holes of the mask (ContourTracer::holes) over A: the
// gap between a crossing tool and one open jaw (triangle) or two (double triangle),
// none where closed jaws cross (cross).
#pragma once

#include <array>
#include <cstdint>

#include "endotower/vision/outer_contour.hpp"

namespace endotower::vision {

enum class GestureFeatureSet { kBook, kExtended, kTopology };

struct GestureFeatures {
    static constexpr int kScanLines = 10;
    static constexpr int kBookCount = 6, kExtendedCount = 9, kTopologyCount = 11;
    bool valid = false;
    double compactness = 0, roughness = 0, elongation = 0, feret_elongation = 0;
    int max_changes = 0, min_changes = 0;
    double solidity = 0, hu1 = 0, hu2 = 0;
    double hole1 = 0, hole2 = 0;
    double centroid_x = 0, centroid_y = 0;  // in mask pixels

    // The classifier's input: the first count(set) of as_vector().
    static constexpr int count(GestureFeatureSet set) {
        return set == GestureFeatureSet::kBook       ? kBookCount
               : set == GestureFeatureSet::kExtended ? kExtendedCount
                                                     : kTopologyCount;
    }
    std::array<float, kTopologyCount> as_vector() const;
};

GestureFeatures measure_gesture_features(const std::uint8_t* mask, int width, int height,
                                         int stride);
// The same with the caller's tracer (reserve()d for the mask's size): no allocation.
GestureFeatures measure_gesture_features(const std::uint8_t* mask, int width, int height,
                                         int stride, ContourTracer& tracer);

}  // namespace endotower::vision
