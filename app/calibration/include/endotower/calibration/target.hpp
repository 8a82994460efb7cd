// Calibration targets for OpenCV's (Zhang's) calibration and their detection.
//   chessboard:COLSxROWS          inner corners; --spacing square size (mm)
//   circles:COLSxROWS             symmetric circle grid; --spacing centre distance
//   asymmetric-circles:COLSxROWS  COLS circles per row, odd rows shifted by half a
//                                 step; --spacing A,B = along a row, between rows
//                                 (one value S means OpenCV's layout: 2S, S). The
//                                 endocal grid (pattern_specs [3, 11, 3, 1]) is 3,1.
//   charuco:COLSxROWS[:DICT]      squares; --spacing SQUARE,MARKER; DICT an OpenCV
//                                 predefined dictionary name (default DICT_4X4_50)
//   squares:COLSxROWS             the book's black-square chart (book model only)
#pragma once

#include <string>
#include <vector>

#include "endotower/calibration/gray_image.hpp"

namespace endotower::calibration {

struct Point3 {
    double x = 0, y = 0, z = 0;
};

enum class TargetKind { kChessboard, kCircles, kAsymmetricCircles, kCharuco, kSquares };

struct TargetSpec {
    TargetKind kind = TargetKind::kChessboard;
    int cols = 0, rows = 0;
    double spacing_a = 1, spacing_b = 1;  // mm (see above)
    std::string dictionary = "DICT_4X4_50";
};

// Parses --target and --spacing ("" = 1 unit). False with `error` saying what is wrong.
bool parse_target(const std::string& target, const std::string& spacing, TargetSpec& out,
                  std::string& error);

// One image's detection: image points and the matching target points (z = 0).
struct View {
    std::string name;
    std::vector<Point2> image_points;
    std::vector<Point3> object_points;
};

// Finds the target in `image` (sub-pixel corners for chessboards and ChArUco). False
// with `error` naming the image and what was missing.
bool detect_target(const GrayImage& image, const TargetSpec& spec, View& out, std::string& error);

}  // namespace endotower::calibration
