// Anchored overlays (issue 7, book ch. 6): an image or a 3-D object fixed to a tracked
// tissue region, moved every frame by the region's homography (marking frame -> now,
// RegionEstimate::homography), so it translates, rotates, scales and tilts with the
// tissue. Pure geometry; AnchoredOverlayStage draws it.
//
// Pixels follow OpenCV (pixel centres at integers), as the region polygons do.
// Camera millimetres: x right, y down, z along the view (hal/overlay_scene.hpp).
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "endotower/hal/overlay_scene.hpp"
#include "endotower/vision/region_tracker.hpp"

namespace endotower::vision {

// Per region: the outline with its markers (RegionStage's drawing), an image from the
// media folder, or a cube standing on the tissue.
enum class RegionOverlayKind { kMarkers, kImage, kObject };
std::string_view to_string(RegionOverlayKind k);  // "markers", "image", "object"
struct RegionOverlay {
    RegionOverlayKind kind = RegionOverlayKind::kMarkers;
    std::string image;  // kImage: the path as written (relative to the media folder)
};
// "markers" | "image:PATH" (PATH relative, inside the media folder: no "..", not
// absolute) | "object:cube". False with `error` saying what is wrong.
bool parse_region_overlay(std::string_view text, RegionOverlay& out, std::string& error);

// The image (width x height px) fitted into the marked polygon's bounding box (aspect
// kept, centred), its corners (top-left, top-right, bottom-right, bottom-left) mapped
// by the homography into this frame. False when a corner maps to or beyond infinity.
bool anchored_image_corners(const RegionEstimate& e, int width, int height,
                            std::array<Point2, 4>& out);

// The tissue plane of a region in the camera: at marking it is taken fronto-parallel
// at `depth_mm` (no depth sensor: the image box's 80 mm by default), its metric extent
// the marked bounding box back-projected there; this frame's pose follows from the
// homography (K^-1 H M = s [r1 r2 t], orthonormalised). The plane frame's origin is
// the bounding box's centre on the tissue, x and y along the image axes at marking,
// z out of the tissue towards the camera at marking is -z.
struct TissuePose {
    bool valid = false;
    std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major, camera <- plane
    Vec3 origin_mm;                                             // the centre on the tissue
    double width_mm = 0, height_mm = 0;                         // the marked box's extent
};
bool tissue_pose(const RegionEstimate& e, const hal::SceneCamera& camera, double depth_mm,
                 TissuePose& out);

// A cube of edge min(width, height) / 2 standing on the tissue at the box's centre.
hal::SceneBox anchored_cube(const TissuePose& pose, const std::array<hal::Rgba8, 6>& faces);

}  // namespace endotower::vision
