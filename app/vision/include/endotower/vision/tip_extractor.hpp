// TipExtractor: the tool tip along the midline (book ch. 4, "Surgical tool tip
// extraction", fig. 4.19-4.21): the largest intensity change of the 1-D profile
// along the midline, searched from the end of the straight edges towards the tip,
// with the book's three filters:
//   1. specular pixels (HSV value >= `specular_value`) are stepped over, never a tip;
//   2. the tip cannot lie beyond the point where the two edges' lines intersect;
//   3. nothing within `border_margin_px` of the field-of-view circle (or the image
//      border) counts: the circle's rim is the sharpest edge in the picture.
// The profile is stepped in x, or in y when the tool is steeper than 45 degrees
// (fig. 4.20), so a vertical tool is searched as well as a horizontal one. Each
// sample averages `profile_halfwidth` pixels either side of the midline.
// Inputs: a BGR24 image, the edge pair, the unit direction from the incision
// towards the tip, the field of view (radius 0: the whole image).
// Output: the tip, the contrast there (0..255) as strength; found=false when the
// search area is empty or no change exceeds `min_contrast`.
#pragma once

#include "endotower/hal/frame.hpp"
#include "endotower/vision/edge_pairing.hpp"

namespace endotower::vision {

struct FieldOfView {
    double cx = 0, cy = 0, radius = 0;  // radius 0: the whole image is in view
};

struct TipExtractorParams {
    int specular_value = 235;
    double border_margin_px = 6.0;
    int profile_halfwidth = 1;
    int min_contrast = 25;
    double search_length_px = 0;  // 0: up to the border
    bool last_strong_change = false;  // false: the book's largest change
    bool use_saturation = false;      // also count changes of HSV saturation
};

struct TipResult {
    bool found = false;
    Point2 tip;
    int contrast = 0;
    bool searched_in_y = false;
};

TipResult extract_tip(const hal::Frame& bgr, const EdgePair& edges, Point2 toward_tip,
                      const FieldOfView& fov, const TipExtractorParams& params = {});

}  // namespace endotower::vision
