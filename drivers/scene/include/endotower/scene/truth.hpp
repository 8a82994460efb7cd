// Ground truth of one rendered frame (docs/truth.md), and its JSON line.
// Pixel members are in the displayed (distorted) image unless named _u (undistorted);
// 3-D members are mm in the camera frame.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "endotower/scene/camera.hpp"
#include "endotower/scene/scenario.hpp"

namespace endotower::scene {

struct Px {
    double x = 0, y = 0;
};

struct MarkerTruth {
    int strip = 0;
    Px center_px;
    std::array<Px, 4> corners_px;  // trapezoid A, B, C, D (book fig. 3.2)
    Vec3 center_mm;
    bool visible = false;
};

struct ToolTruth {
    int id = 0;
    bool visible = false;
    double visible_fraction = 0;
    Px tip_px, tip_px_u, head_px, head_px_u;
    double axis_deg = 0, width_px = 0;
    std::array<std::array<double, 4>, 2> edges_px{};
    std::array<double, 4> midline_px{};
    Vec3 tip_mm, head_mm, axis_dir, pivot_mm;
    double yaw_deg = 0, pitch_deg = 0, roll_deg = 0, diameter_mm = 5;
    std::string tip_type, jaw, gesture;
    std::vector<MarkerTruth> markers;
};

struct RegionTruth {
    int id = 0;
    std::vector<Px> polygon_px;
    std::array<double, 9> h_from_first{};
    double visible_fraction = 0;
    std::string change;
};

struct TargetTruth {
    std::string kind;  // white, squares, checkerboard, two_dot, grid_lines
    double distance_mm = 0;
    std::vector<Vec3> points_mm;
    std::vector<Px> points_px, points_px_u;
};

struct FrameTruth {
    int frame = 0;
    std::int64_t t_ns = 0;
    double light = 0, speed_cm_s = 0;
    std::vector<ToolTruth> tools;
    std::string gesture;  // empty = null
    std::vector<RegionTruth> regions;
    std::vector<std::string> events;
    bool has_target = false;
    TargetTruth target;
};

// One line of truth.jsonl (no trailing newline). `scenario` supplies the factors.
std::string truth_json_line(const FrameTruth& t, const CameraModel& cam, const Scenario& scenario);

}  // namespace endotower::scene
