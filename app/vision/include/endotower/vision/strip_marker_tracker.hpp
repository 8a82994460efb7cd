// StripMarkerTracker: black strip markers on a tool's shaft (book ch. 3, figs. 3.1,
// 3.2, eq. 3.1-3.2): the trapezoid ABCD of the visible strip nearest the tip, its
// centre E, the apparent diameter M -> depth, E -> millimetres. docs/markers.md.
// Per frame (BGR24 or GREY8; buffers sized in configure(), no exceptions):
//  1. tool parts: grey opening removes bright lines thinner than `min_band_fraction`
//     (0.025) x height; tool = brighter than the lit picture's median by
//     max(min_contrast / 2, bright_margin (0.25) x median); binary opening, same size;
//  2. a strip lies between two parts: their joint convex hull minus the parts, >=
//     `dark_fill` (0.6) darker than `dark_ratio` (0.5) x the local tool brightness
//     (grey max over `window_fraction` (0.1) x height), mean < dark_ratio x both parts;
//  3. blob analysis: u from part to part; AB, CD where the parts end; M across u from
//     the silhouettes (the dark limb under coaxial light), the wider side; E along u
//     where the rings' front-arc displacement vanishes (strip middles at 0 and +-0.8 r);
//  4. strips sharing a part are one tool's; the strip nearest the tip is the one
//     farthest from the shaft when exactly one part leaves the picture, else the
//     book's: the smallest M (undistorted). One or two occluded strips leave the
//     others usable.
// set_calibration: E and M undistorted; M divided by the off-axis magnification of a
// round section; depth from the table (diameter_mm against marker_mm); x, y by eq.
// 3.1/3.2, the principal point as offsets; depth_pinhole_mm = fx D / M cross-checks.
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
    double bright_margin = 0.25;
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
