// Motion of the tools about their incision points and of the endoscope (private).
//
// A tool's pose is carried by its head (the shaft's end, rigid whatever the jaws do);
// a segment moves one anchor point (tip, head or first marker strip) at constant speed
// along its path, and the head follows on the line from the pivot through the anchor.
// The endoscope's segments move the camera pose in the world frame (the first frame's
// camera frame).
#pragma once

#include <string>
#include <vector>

#include "endotower/scene/scenario.hpp"

namespace endotower::scene::detail {

struct JawGeometry {
    double length, r_open, r_closed, half_angle_deg;
};
JawGeometry jaw_geometry(TipType tip, double diameter_mm);
// Signed distance from the head to the anchor along the axis towards the pivot.
double anchor_offset(const ToolSpec& t, Anchor a, Jaw jaw);

// Unit direction pivot -> tip from yaw/pitch (docs/scenario.md) and back.
Vec3 direction_from_angles(double yaw_deg, double pitch_deg);
void angles_from_direction(Vec3 u, double& yaw_deg, double& pitch_deg);

struct ToolPose {
    Vec3 head, tip, axis;  // world mm; axis: unit, head -> pivot
    double roll_deg = 0;
    Jaw jaw = Jaw::kClosed;
    bool dwell = false, loop = false;
};

class ToolMotion {
public:
    void compile(const ToolSpec& spec, double fps, double duration_s, std::uint64_t seed);
    ToolPose at(double t) const;

private:
    struct Seg {
        SegmentType type{};
        double t0 = 0, t1 = 0;
        double e = 0;  // anchor offset
        Jaw jaw{};
        double roll0 = 0, roll1 = 0;
        Vec3 a0, a1, center;
        double yaw0 = 0, pitch0 = 0, depth0 = 0, yaw1 = 0, pitch1 = 0, depth1 = 0;
        double radius = 0, turns = 0;
        std::vector<Vec3> pts;
        std::vector<double> cum;
    };
    ToolPose pose_from_anchor(Vec3 q, double e, Jaw jaw, double roll) const;
    ToolSpec spec_;
    std::vector<Seg> segs_;
    ToolPose start_;
};

struct CameraPose {
    Mat3 r_wc;  // camera -> world rotation
    Vec3 c;     // centre, world
    // World point -> camera frame.
    Vec3 to_camera(Vec3 w) const { return r_wc.transposed() * (w - c); }
};

class CameraMotion {
public:
    // plane_n, plane_o: the tissue plane (world), for zoom and orbit distances.
    void compile(const std::vector<CameraSegment>& segs, double fps, Vec3 plane_n, Vec3 plane_o);
    CameraPose at(double t) const;
    std::string change_at(double t) const;
    double background_at(double t) const;  // 0..1 blend to the changed background
    bool moving() const { return moving_; }

private:
    struct Seg {
        CameraSegment spec;
        double t0 = 0, t1 = 0, d0 = 0;
        CameraPose start;
    };
    std::vector<Seg> segs_;
    bool moving_ = false;
};

}  // namespace endotower::scene::detail
