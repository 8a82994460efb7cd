// A scenario: everything the simulator renders, as read from a YAML file
// (docs/scenario.md has the format, with every field and its default).
//
// load_scenario() reads and checks a file; on a bad file it returns false with
// `error` = "FILE:LINE: FIELD: what is wrong" (LINE 1-based, FIELD a path like
// tools[0].motion[2].speed_cm_s). Unknown fields are errors, so typos do not pass.
// Relative paths inside (tissue.image) are resolved against the file's directory.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "endotower/scene/camera.hpp"
#include "endotower/scene/vec.hpp"

namespace endotower::scene {

enum class TipType { kGrasper, kScissors };
enum class Jaw { kOpen, kClosed };
enum class Material { kDark, kMetal };

struct TissueSpec {
    double distance_mm = 110, tilt_deg[2] = {24, -10};  // at the optical axis; about x, y
    double vessels = 0.5, fat = 0.25, wetness = 0.4, blood = 0.0;  // 0..1 amounts
    std::string image;  // optional real picture used as the tissue albedo
};

enum class TargetKind { kNone, kWhite, kSquares, kCheckerboard, kTwoDot, kGridLines };
struct TargetSpec {
    TargetKind kind = TargetKind::kNone;
    double pitch_mm = 8, size_mm = 4, line_mm = 0.6, dot_mm = 4, separation_mm = 10;
    int cols = 9, rows = 7;  // squares / inner corners
    std::vector<double> distances_mm = {50};
    std::vector<double> frames_per_distance = {1};  // one, or one per distance
    double offset_mm[2] = {0, 0};                   // pattern centre off the optical axis
};

struct MarkerSpec {
    int count = 0;
    double width_mm = 3, gap_mm = 3, offset_mm = 12;  // offset: head -> first strip start
};

enum class Anchor { kTip, kHead, kMarker };
enum class SegmentType { kMove, kPose, kDwell, kLoop, kWander };
struct Segment {
    SegmentType type = SegmentType::kDwell;
    Vec3 to;                                          // kMove: anchor point (world mm)
    double yaw_deg = 0, pitch_deg = 0, depth_mm = 0;  // kPose
    double speed_cm_s = 0, frames = 0;                // one sets the duration
    double radius_mm = 8, turns = 1;                  // kLoop
    double box_mm = 15;                               // kWander half size
    Anchor anchor = Anchor::kTip;
    std::optional<double> roll_deg;  // reached at the segment's end
    std::optional<Jaw> jaw;          // from the segment's start
};

struct ToolSpec {
    int id = 0;
    double diameter_mm = 5;
    TipType tip = TipType::kGrasper;
    Jaw jaw = Jaw::kClosed;
    Material shaft = Material::kDark;
    Vec3 pivot{70, -50, 10};
    Vec3 start_point;  // start anchor point, or pose below
    bool start_is_pose = false;
    double start_yaw = 0, start_pitch = 0, start_depth = 80;
    Anchor start_anchor = Anchor::kTip;
    double roll_deg = 0;
    std::optional<std::array<double, 3>> color;  // flat unlit BGR 0..255 (test scenes)
    MarkerSpec markers;
    std::vector<Segment> motion;
    bool repeat = false;
};

struct DistractorSpec {
    double diameter_mm = 5;
    Material material = Material::kDark;
    Vec3 from[2], to[2];  // end points at the first and the last frame
};

struct OccluderSpec {
    Vec3 from, to;  // centre at the first and last frame
    double radius_mm[2] = {15, 10};
};

enum class CameraMove { kTranslate, kRotate, kZoom, kOrbit, kHold };
struct CameraSegment {
    CameraMove move = CameraMove::kHold;
    Vec3 by;                       // kTranslate, camera frame at the segment start
    double deg = 0;                // kRotate, about the optical axis
    double zoom = 1;               // kZoom: apparent scale of the tissue at the end
    double orbit_deg[2] = {0, 0};  // kOrbit: yaw, pitch about the viewed tissue point
    double frames = 10;
    std::string change;       // truth label override
    bool background = false;  // the tissue outside the regions changes meanwhile
};

// Tissue pushed within its plane (table 6.6's deformation): a smooth local
// displacement D(u, v) = s(t) push exp(-|(u, v) - centre|^2 / (2 radius^2)), s ramping
// 0 -> 1 (smoothstep) over `frames` from `from_frame`. Off when push is zero.
struct DeformationSpec {
    double center_mm[2] = {0, 0};
    double radius_mm = 12;
    double push_mm[2] = {0, 0};
    double from_frame = 0, frames = 10;
    bool on() const { return push_mm[0] != 0 || push_mm[1] != 0; }
};

struct RegionSpec {
    int id = 0;
    std::vector<std::array<double, 2>> polygon_mm;  // on the tissue plane (docs)
};

using FactorValue = std::variant<std::string, double, bool>;

struct Scenario {
    std::string path, name, description;
    int frames = 50, width = 640, height = 480;
    double fps = 25;
    std::uint64_t seed = 1;
    CameraSpec camera;
    TissueSpec tissue;
    TargetSpec target;
    std::vector<ToolSpec> tools;
    std::vector<DistractorSpec> distractors;
    std::vector<OccluderSpec> occluders;
    std::vector<CameraSegment> endoscope;
    std::vector<RegionSpec> regions;
    DeformationSpec deformation;
    double light_from = 0.8, light_to = 0.8;
    double noise = 1.5;        // sensor noise sigma, 8-bit levels
    double motion_blur = 0.0;  // exposure, fraction of the frame period
    double smoke = 0.0, smoke_from_frame = 0;
    double flash_rate = 0.0;  // probability of a specular flash per frame
    std::vector<std::pair<std::string, FactorValue>> factors;
};

bool load_scenario(const std::string& path, Scenario& out, std::string& error);
// Same, from text; `name` stands for the file in messages.
bool parse_scenario(const std::string& text, const std::string& name, Scenario& out,
                    std::string& error);
// Multiplies every duration given in frames (total, segments, holds) by `scale`.
void scale_durations(Scenario& s, double scale);

}  // namespace endotower::scene
