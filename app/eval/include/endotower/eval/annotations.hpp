// Readers for the real annotation formats in ../shared/data (see its README.md).
//
// Sznitman train.xml: <frame><PositionIndex> N </PositionIndex><tool> ROW COL SCALE
//   ANGLE </tool>...</frame>, 0-2 tools per frame. ROW,COL = head pixel (y, x); ANGLE
//   radians, (cos a, sin a) points from the head back along the shaft (the same
//   direction as the trace's axis_deg); SCALE a size in px. A frame index listed
//   again is dropped (the first is kept) and counted in `duplicates_dropped`.
// Tool mask: 8-bit PNG, nonzero = instrument; each 8-connected component of at
//   least `min_area` px is one instrument (bbox inclusive, principal axis as a line).
// Homography: OpenCV FileStorage (.xml/.yml/.yaml, the first matrix node, 3x3) or a
//   text file of 9 numbers (homography_pairs *_model.txt, which maps B to A).
// Errors name the file (and line where there is one), e.g. "train.xml:12: ...".
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "endotower/eval/truth.hpp"

namespace endotower::eval {

struct SznitmanTool {
    double row = 0, col = 0, scale = 0, angle_rad = 0;
    Point2 head() const { return {col, row}; }
};
struct SznitmanFrame {
    int index = 0;  // PositionIndex (the frame file's number)
    int line = 0;   // line of its <frame> in the file
    std::vector<SznitmanTool> tools;
};
struct SznitmanAnnotations {
    int declared_frames = -1;  // <numberOfFrames>, -1 if absent
    int duplicates_dropped = 0;
    std::vector<SznitmanFrame> frames;  // in file order, unique indices
    int tool_frames() const;
};
bool read_sznitman(const std::string& path, SznitmanAnnotations& out, std::string& error);

struct MaskComponent {
    int area = 0;
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // inclusive bounding box
    Point2 centroid;
    double axis_deg = 0;  // principal axis as a line, in [0, 180)
};
struct ToolMask {
    int width = 0, height = 0;
    std::vector<std::uint8_t> on;  // width*height, 1 = instrument
    std::vector<MaskComponent> components;  // largest first
};
bool read_tool_mask(const std::string& path, ToolMask& out, std::string& error, int min_area = 50);

using Homography = std::array<double, 9>;  // row-major 3x3
// The matrix as stored in the file (FileStorage: as written; *_model.txt: B to A).
bool read_homography(const std::string& path, Homography& out, std::string& error);
Point2 apply_homography(const Homography& h, Point2 p);
bool invert_homography(const Homography& h, Homography& out);

}  // namespace endotower::eval
