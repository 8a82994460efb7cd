// RegionTracker: keeps tissue regions, polygons marked on one frame, located in later
// frames (book ch. 6), so an overlay stays anchored to the tissue.
//
// mark(): local features (SIFT, ORB or AKAZE; SURF is patented and not in Debian's
//   OpenCV) detected inside the polygon's mask on the marking frame form the region's
//   keyframe. Polygons are in that frame's pixels; at most kMaxVertices vertices.
// track(), every frame:
//   propagation  pyramidal Lucas-Kanade moves the region's features from the previous
//                frame; a RANSAC homography from their keyframe positions (eq. 6.4-6.5)
//                places the polygon. About 1.5 ms at 1080p; no heap allocation.
//   keyframe     the keyframe's descriptors are matched by brute force (L2 / Hamming)
//   matching     against the frame's: Lowe's ratio test, then the book's filter (keep
//                matches shorter than the average distance), RANSAC homography. Runs on
//                the first frame after mark(), every `redetect_interval` frames (drift
//                correction, in a window around the propagated polygon), after a format
//                change (image pairs of different sizes), and on every frame while the
//                region is lost (whole frame, recovery). Frames wider than
//                detect_max_width are downscaled for it; results are in the input's pixels.
// bend: tissue is not a plane. Propagated points off the homography by up to 15 % of the
//   region's size are kept as its local motion, and each vertex is moved by the offsets
//   of the points around it (a Gaussian-weighted local linear fit at the vertex, sigma
//   20 % of the region's size): the outline follows a push or a fold; under rigid motion
//   the offsets are noise and the outline stays the homography's.
// A region is lost when fewer than min_inliers features agree or the homography is
// implausible (flipped, collapsed, or the polygon out of the picture). Propagation
// allocates nothing in steady state (its LK, high-pass image and RANSAC are the
// project's own, sized in mark() and on a frame size change: OpenCV's allocate per
// call); keyframe matching (OpenCV's detectors and findHomography) allocates.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "endotower/hal/frame.hpp"
#include "endotower/vision/tool_pose.hpp"

namespace endotower::vision {

enum class RegionDescriptor { kSift, kOrb, kAkaze };
std::string_view to_string(RegionDescriptor d);
bool parse_region_descriptor(std::string_view name,
                             RegionDescriptor& out);  // "sift", "orb", "akaze"

struct RegionTrackerParams {
    RegionDescriptor descriptor = RegionDescriptor::kSift;
    int redetect_interval = 10;  // frames between drift corrections while tracked; 0 = never
    int min_inliers = 10;        // fewer agreeing features: lost
    double ratio = 0.8;          // Lowe's ratio test
    double ransac_px = 3.0;      // RANSAC reprojection threshold, input pixels
    int detect_max_width = 640;  // keyframe matching on frames downscaled to this width
    bool propagate = true;       // false: keyframe matching on every frame (the book's method)
    bool bend = true;            // the outline follows tissue that bends (see track())
};

enum class RegionState { kTracked, kLost };
std::string_view to_string(RegionState s);  // "tracked", "lost"

struct RegionEstimate {
    static constexpr std::size_t kMaxVertices = 16;
    int id = 0;
    RegionState state = RegionState::kLost;
    std::array<Point2, kMaxVertices> polygon{};  // tracked: this frame; lost: last known
    std::size_t vertices = 0;
    int inliers = 0;              // features agreeing with the homography this frame
    bool keyframe_match = false;  // this frame's estimate came from keyframe matching
    // The polygon as marked (the marking frame's pixels) and the region's homography from
    // the marking frame to this one, row-major (eq. 6.4; the last known while lost): what
    // an anchored overlay is moved by. `polygon` may bend away from it (see track()).
    std::array<Point2, kMaxVertices> marked{};
    std::array<double, 9> homography{1, 0, 0, 0, 1, 0, 0, 0, 1};
};

class RegionTracker {
public:
    static constexpr std::size_t kMaxRegions = 8;
    explicit RegionTracker(RegionTrackerParams params = {});
    ~RegionTracker();
    RegionTracker(const RegionTracker&) = delete;
    RegionTracker& operator=(const RegionTracker&) = delete;

    const RegionTrackerParams& params() const;
    // Marks (or re-marks) region `id` on `frame`. False, with `error` saying why, when the
    // polygon is degenerate or out of the frame, has too many vertices, the tracker is
    // full, the pixel format is unsupported, or too few features lie inside it.
    bool mark(int id, std::span<const Point2> polygon, const hal::Frame& frame, std::string& error);
    // Locates every region in `frame`; writes one estimate per region (in mark order)
    // into out and returns how many. Bgr24, Rgb24, Bgra32 and Gray8 frames.
    std::size_t track(const hal::Frame& frame, std::span<RegionEstimate> out);
    std::size_t size() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::vision
