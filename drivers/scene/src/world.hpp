// The scene at one instant, in the camera frame, ready for ray casting (private):
// the tissue plane or calibration target behind everything, and the tools'
// shafts and jaws, distractor rods and tissue flaps in front, each with a
// conservative box in the undistorted image so that a pixel tests only what can
// cover it. SceneModel holds what is fixed for the recording and builds a
// FrameWorld for any time t.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "endotower/scene/camera.hpp"
#include "endotower/scene/scenario.hpp"
#include "motion.hpp"
#include "tissue.hpp"

namespace endotower::scene::detail {

struct Box {
    float x0 = 1, y0 = 1, x1 = 0, y1 = 0;  // empty by default
    bool contains(float x, float y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
    void add(const Box& b);
};

enum class Surface : std::uint8_t {
    kNone,
    kTissue,
    kTarget,
    kShaft,
    kMetal,
    kStrip,
    kJaw,
    kFlap,
    kFlat
};

struct Shaft {
    Vec3 head, axis;
    double r = 2.5, len = 200, collar = 0;
    Material mat = Material::kDark;
    double strips[8][2] = {};
    int nstrips = 0, id = 0, tool = -1;
    const float* flat = nullptr;  // unlit colour (linear radiance), test scenes
    Box box;
};
struct Capsule {
    Vec3 a, b;
    double r = 1;
    Material mat = Material::kMetal;
    bool jaw = false, serrated = false;
    int id = 0, tool = -1;
    const float* flat = nullptr;
    Box box;
};
struct Flap {
    Vec3 c;
    double rx = 10, ry = 10;
    int id = 0;
    Box box;
};

struct Hit {
    double t = std::numeric_limits<double>::infinity();
    Vec3 n;
    Surface surface = Surface::kNone;
    int id = 0, tool = -1;
    double along = 0;  // shaft: mm from the head; jaw: mm from the hinge
    const float* flat = nullptr;
    Material mat = Material::kDark;
    bool serrated = false;  // grasper jaws: cross grooves
};

struct ToolState {  // camera frame
    ToolPose pose;  // head, tip, axis (camera frame), roll, jaw, events
    Vec3 pivot, open_dir;
    Vec3 jaw_end[2];  // extreme points of the jaws (one when closed)
};

struct FrameWorld {
    CameraPose cam;
    Vec3 pn, po, pe1, pe2;  // tissue or target plane (camera frame), pn facing the camera
    double ph = 0;          // dot(pn, X) = ph on the plane
    bool target = false;
    double target_z = 0;
    std::vector<ToolState> tools;
    std::vector<Shaft> shafts;
    std::vector<Capsule> caps;
    std::vector<Flap> flaps;
    double light = 1, background = 0;
    double deform = 0;  // strength of the tissue deformation, 0..1
    double exposure = 1;  // auto exposure: less gain when the background is near

    // Nearest hit among the objects in front of the plane (skipping `skip_tool`).
    Hit trace(Vec3 d, float xu, float yu, int skip_tool = -1) const;
    // Distance along unit ray d to the plane; infinity when it does not face it.
    double plane_t(Vec3 d) const {
        const double dn = dot(pn, d);
        return dn < -1e-9 ? ph / dn : std::numeric_limits<double>::infinity();
    }
};

struct SceneModel {
    Scenario sc;
    std::uint64_t seed = 1;
    CameraModel cam;
    std::vector<ToolMotion> tools;
    CameraMotion endoscope;
    Vec3 plane_n, plane_o, plane_e1, plane_e2;  // world
    TissueTexture tex, tex2;
    std::vector<std::array<float, 3>> flat_colors;  // per tool, linear radiance

    bool init(const Scenario& s, std::uint64_t seed, std::string& error);
    double time_of(int frame) const { return frame / sc.fps; }
    double light_at(int frame) const;
    double target_distance(int frame) const;
    FrameWorld world_at(double t, int frame) const;
    bool inside_regions(double u, double v) const;
    double deform_at(double t) const;
    // The deformation's displacement of tissue point (u, v) at strength s (forward),
    // and the tissue point that lands on plane point (u, v) (its inverse).
    void displace(double u, double v, double s, double& du, double& dv) const;
    void undeform(double& u, double& v, double s) const;
};

}  // namespace endotower::scene::detail
