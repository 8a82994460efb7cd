// EdgePairing: from the straight segments of a frame (Canny + probabilistic Hough),
// the tool's two edges and midline (book ch. 4, "Initialization and Preprocessing",
// steps e and f, fig. 4.9, eq. 4.12, 4.13).
//
// Inputs: segments, strongest (longest) first; bin_distance_px (10, the book's
// threshold): a segment whose end points are all within it of a bin's first line
// joins that bin; the first segment beyond it opens the second bin; others are
// dropped. max_angle_deg (8): segments more oblique than that to bin 1 never open
// bin 2 (a shaft's edges are nearly parallel in the image).
// Outputs: per bin, one edge joining its extreme end points along the bin's
// direction (leftmost to rightmost, or top to bottom for steep tools); the midline
// between them (eq. 4.13, averaged in the parameterisation both edges share).
#pragma once

#include <span>

#include "endotower/vision/line2.hpp"

namespace endotower::vision {

struct EdgePairingParams {
    double bin_distance_px = 10.0;
    double max_angle_deg = 8.0;
};

struct EdgePair {
    bool found = false;  // both bins hold a segment
    Segment e1, e2, midline;
    double width_px = 0;  // distance between the edges at the midline's centre
};

EdgePair pair_edges(std::span<const Segment> segments, const EdgePairingParams& params = {});

}  // namespace endotower::vision
