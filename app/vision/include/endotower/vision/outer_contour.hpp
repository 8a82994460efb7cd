// ContourTracer: the outer borders of the 8-connected blobs of a binary mask and the
// convex hull of a polygon, allocation-free once reserve()d, with exactly the vertices
// OpenCV gives (tested against it):
//   largest()  the outer border of every blob, traced as cv::findContours(RETR_EXTERNAL,
//              CHAIN_APPROX_SIMPLE) does (Suzuki-Abe border following from the blob's
//              first pixel in raster order; a vertex wherever the direction changes),
//              in the mask's coordinates + (1, 1) (as traced on a copy with a one-pixel
//              zero border); returns the one of at least 3 vertices with the largest
//              |area| (equal areas: the last in raster order), empty when none;
//   hull()     the strictly convex hull of the points (no collinear or repeated
//              vertices, the vertex set of cv::convexHull), counter-clockwise;
//   holes()    once after largest(): the pixel counts of the two largest holes of its
//              mask, background regions (4-connected, the dual of 8-connected blobs)
//              that the picture's border cannot reach: the gaps an open jaw and a
//              crossing tool close (cv::findContours RETR_CCOMP's inner borders).
// reserve() sizes the buffers for masks up to width x height (the only allocation);
// larger masks are refused (empty). No exceptions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace endotower::vision {

struct IntPoint {
    int x = 0, y = 0;
};

class ContourTracer {
public:
    void reserve(int width, int height);
    std::span<const IntPoint> largest(const std::uint8_t* mask, int width, int height,
                                      std::size_t stride, double& area);
    std::span<const IntPoint> hull(std::span<const IntPoint> points);
    void holes(int& largest, int& second);

private:
    int width_ = 0, height_ = 0;
    int last_width_ = 0, last_height_ = 0;  // the last largest() mask's size
    std::vector<std::int8_t> image_;  // bordered copy: 0 background, 1 blob, 2 done, 3 reached
    std::vector<std::int32_t> stack_;
    std::vector<IntPoint> contour_, best_, sorted_, hull_;
};

// |area| of a closed polygon (the shoelace sum, as cv::contourArea) and its perimeter
// (float edge lengths summed in double, as cv::arcLength(closed)).
double polygon_area(std::span<const IntPoint> p);
double polygon_perimeter(std::span<const IntPoint> p);

}  // namespace endotower::vision
