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
// none where closed jaws cross (cross). The profile features (kProfile: the eleven and
// 2 x kProfileStations) come from measure_tip_profile(): the region's width across the
// shaft's axis and its runs there at stations back from the tip, so a jaw's thickness
// against the shaft's (a grasper's jaw is about twice a scissors blade's) and the gap
// between open jaws are read in the tool's own frame, whatever its roll in the picture.
#pragma once

#include <array>
#include <cstdint>

#include "endotower/vision/outer_contour.hpp"

namespace endotower::vision {

enum class GestureFeatureSet { kBook, kExtended, kTopology, kProfile };

struct GestureFeatures {
    static constexpr int kScanLines = 10;
    static constexpr int kBookCount = 6, kExtendedCount = 9, kTopologyCount = 11;
    static constexpr int kProfileStations = 10;
    static constexpr int kProfileCount = kTopologyCount + 2 * kProfileStations;
    bool valid = false;
    double compactness = 0, roughness = 0, elongation = 0, feret_elongation = 0;
    int max_changes = 0, min_changes = 0;
    double solidity = 0, hu1 = 0, hu2 = 0;
    double hole1 = 0, hole2 = 0;
    // Station k at (0.35 + 0.7 k) r from the tip: width / 2r, runs of region pixels.
    std::array<float, kProfileStations> profile_width{}, profile_runs{};
    double centroid_x = 0, centroid_y = 0;  // in mask pixels

    // The classifier's input: the first count(set) of as_vector().
    static constexpr int count(GestureFeatureSet set) {
        return set == GestureFeatureSet::kBook       ? kBookCount
               : set == GestureFeatureSet::kExtended ? kExtendedCount
               : set == GestureFeatureSet::kTopology ? kTopologyCount
                                                     : kProfileCount;
    }
    std::array<float, kProfileCount> as_vector() const;
};

GestureFeatures measure_gesture_features(const std::uint8_t* mask, int width, int height,
                                         int stride);
// The same with the caller's tracer (reserve()d for the mask's size): no allocation.
GestureFeatures measure_gesture_features(const std::uint8_t* mask, int width, int height,
                                         int stride, ContourTracer& tracer);
// Whether measure_gesture_features() would give valid features, without measuring them.
bool gesture_features_valid(const std::uint8_t* mask, int width, int height, int stride,
                            ContourTracer& tracer);
// Fills f's profile: the tip at (tip_x, tip_y) in mask pixels, (axis_x, axis_y) the unit
// direction from the tip back along the shaft, `radius` the shaft's radius (pixels).
// Each station samples the line across the axis every half pixel for 8 radii either side
// (outside the mask is empty); a run is at least two samples, and a gap of under four
// samples (2 px) does not end it (a crack in a jaw's mask). No allocation.
void measure_tip_profile(const std::uint8_t* mask, int width, int height, int stride, double tip_x,
                         double tip_y, double axis_x, double axis_y, double radius,
                         GestureFeatures& f);

}  // namespace endotower::vision
