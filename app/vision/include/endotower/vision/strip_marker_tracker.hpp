// StripMarkerTracker: black strip markers on a tool's shaft (book ch. 3, figs. 3.1,
// 3.2, eq. 3.1-3.2): the strips, the trapezoid ABCD of the visible strip nearest the
// tip and its centre E, the apparent tool diameter M -> depth, E -> millimetres.
//
// Per frame (BGR24 or GREY8, any size; buffers sized in configure()):
//  1. tool parts: thin bright structures (narrower than `min_band_fraction` x height,
//     e.g. grid lines) are removed by a grey opening; the local tool brightness L is
//     the grey maximum of that over a square of `window_fraction` x height; a pixel is
//     tool where it is at least `bright_ratio` (0.6) x L and L shows `min_contrast`
//     (24) over the local minimum; a binary opening of the same size keeps the bands;
//  2. a strip lies between two tool parts (the bright bands of fig. 3.1): the convex
//     hull of two parts minus the parts, at least `dark_fill` (0.6) dark (below
//     `dark_ratio` (0.5) x L) and no other part inside;
//  3. blob analysis of that region: E its centroid, the axis u from part to part,
//     A, B the extremes across u on the side of the first part, C, D on the other;
//     M the region's width across u through E;
//  4. strips sharing a part belong to one tool; the strip with the smallest M is the
//     one nearest the tip (book: "the smallest M is the one closest to the surgical
//     site"), so one or two occluded strips leave the others usable.
// With a calibration (set_calibration) E and M are undistorted, depth comes from the
// separation table (diameter_mm against the table's marker_mm), x, y from eq. 3.1/3.2
// with the principal point as offsets; depth_pinhole_mm = fx D / M is the cross-check.
// No exceptions; a frame without strips gives no markers.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <span>

#include "endotower/calibration/separation_table.hpp"
#include "endotower/hal/frame.hpp"
#include "endotower/vision/tool_pose.hpp"

namespace endotower::vision {

struct StripMarkerParams {
    double diameter_mm = 5.0;          // the tool's diameter under the strips
    double window_fraction = 0.1;      // local brightness window, x frame height
    double min_band_fraction = 0.025;  // narrowest tool band kept, x frame height
    double bright_ratio = 0.5, dark_ratio = 0.5, dark_fill = 0.6;
    int min_contrast = 24, min_level = 12, unlit_level = 4;
    double bright_margin = 0.25, taper = 0.04;
};

struct StripMarker {
    Point2 a, b, c, d, e;  // trapezoid ABCD and its centre E, input pixels
    double diameter_px = 0;
    int strips = 0;        // strips seen on this tool
    bool located = false;  // depth and mm below are valid (calibrated)
    double depth_mm = 0, depth_pinhole_mm = 0;
    Vec3 e_mm;  // E in the camera frame (eq. 3.1/3.2, depth)
};

class StripMarkerTracker {
public:
    static constexpr std::size_t kMaxMarkers = 2;
    explicit StripMarkerTracker(StripMarkerParams params = {});
    ~StripMarkerTracker();
    StripMarkerTracker(StripMarkerTracker&&) noexcept;
    const StripMarkerParams& params() const { return params_; }
    // `undistort` maps an input pixel to the corrected image of `camera` (no allocation).
    void set_calibration(const calibration::SeparationTable& table, const PinholeCamera& camera,
                         std::function<Point2(Point2)> undistort);
    void configure(const hal::FrameFormat& format);
    std::size_t track(const hal::Frame& frame, std::span<StripMarker, kMaxMarkers> out);

private:
    struct Work;
    void locate(StripMarker& m) const;
    double undistorted_diameter(Point2 e, Point2 a, Point2 b, double diameter) const;
    StripMarkerParams params_;
    calibration::SeparationTable table_;
    PinholeCamera camera_{};
    std::function<Point2(Point2)> undistort_;
    std::unique_ptr<Work> work_;
};

}  // namespace endotower::vision
