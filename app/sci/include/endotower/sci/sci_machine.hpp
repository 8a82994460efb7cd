// SciMachine: the surgeon-computer interface's one state machine (docs/sci.md has the
// diagram). One step() per analysed frame with that frame's tools, gesture and handle
// events; times are the frames' capture times, so dwell and hold times are exact on
// the virtual clock (a 2.0 s dwell clicks on the first frame at >= 2.0 s, not before).
//
// States: inactive, activating (scissors held still in the activation area at the
// bottom of the image, fig. 3.31), menu (pointing, nothing highlighted), highlight
// (the item under the tip or chosen by the wheel; the tip's item clicks after
// `dwell_ms`), confirm (an item selected with the open grasper, the one under its jaws'
// tip, else the one under the tip or the one the tip left during the grasper's hold or
// `select_grace_ms` before it, waits `confirm_ms` for a loop of the jaws' tip: a loop
// confirms, anything else denies, fig. 3.32/3.33), grabbed (the image box follows the
// tool, eq. 4.33).
// Inputs: button press = activate / click the highlighted item / place the box;
// long press = deactivate; wheel = move the highlight (images in the viewer); a cross
// held `cross_hold_ms` opens the quadrant menu when inactive and deactivates otherwise.
// A cross is held only while the tracked tools are still, too: each tool's tip within
// `still_fraction` x width of where it was when the hold began (a tool sliding along its
// shaft leaves the crossing, and so the gesture's region, unchanged: surgery, not a
// command; docs/sci.md "False activations"). Nor is a cross that forms out of a triangle
// or double triangle while the tools touch: jaws closing over the other tool (a grasp);
// a commanded cross is made with closed jaws, the tools coming together. A frame more
// than `part_ms` after the tools last touched ends that crossing (docs/sci.md "A cross
// formed by a grasp").
// event() names what happened this frame (docs/sci.md lists them), or is empty.
// Params defaults: layout three_level, dwell 2000 ms, activation hold 3000 ms, cross
// hold 1000 ms, confirm window 2000 ms, select grace 200 ms, loop 5 of 8 directions,
// activation area the bottom 20 % x middle 40 % of the frame. No allocation after
// configure().
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "endotower/hal/control_input.hpp"
#include "endotower/sci/sci_functions.hpp"
#include "endotower/sci/sci_menu.hpp"

namespace endotower::sci {

enum class SciState : std::uint8_t {
    kInactive,
    kActivating,
    kMenu,
    kHighlight,
    kConfirm,
    kGrabbed
};
std::string_view to_string(SciState s);

// kOpenCrossing: two tools crossing, one or both with open jaws (triangle, double triangle).
enum class SciGesture : std::uint8_t {
    kNone,
    kOpenGrasper,
    kScissors,
    kCross,
    kOpenCrossing,
    kOther
};

struct SciTool {
    double x = 0, y = 0;  // tip, px
    bool has_3d = false;
    Vec3d tip_mm, axis_dir;
};

struct SciFrame {
    hal::Nanos t_ns = 0;
    std::array<SciTool, 2> tools{};
    int tool_count = 0;  // tools[0] is the cursor
    SciGesture gesture = SciGesture::kNone;
    double gesture_held_ms = 0;  // held still this long (GestureHold)
    bool gesture_fired = false;  // the frame the hold reached the gesture stage's hold time
    double gesture_x = 0, gesture_y = 0;  // the gesture's tip, px
    bool tools_touching = false;          // a region holds two tools (GestureFrame::touching)
    bool gesture_dropout = false;         // the held gesture is not this frame's own (GestureHold)
    std::span<const hal::ControlEvent> events;
};

struct SciParams {
    SciLayout layout = SciLayout::kThreeLevel;
    double dwell_ms = 2000, activation_hold_ms = 3000, cross_hold_ms = 1000, confirm_ms = 2000;
    // The loop, read on the jaws' tip (the gesture's; the tracked tip without one),
    // averaged over `loop_mean_ms`, in steps of at least `loop_step_fraction` of the
    // height: it confirms once the steps have gone in `loop_sectors` of the eight
    // 45-degree directions (one turn goes in 5-8, a stroke and back in 4 or fewer with the
    // jaws' tip's jitter; docs/sci.md, "Select and loop", "The loop on the jaws' tip").
    int loop_sectors = 5;
    double loop_step_fraction = 0.015;
    double loop_mean_ms = 240;
    // An item the tip left this long before the open grasper's hold began is still the
    // one selected: the hold's start lags the jaws' opening by up to the gesture hold's
    // dropout tolerance (GestureHoldParams::dropout_ms, 200), while opening them moves
    // the tracked tip.
    double select_grace_ms = 200;
    // The item under the tip stays until the tip is this far outside it (x width): the
    // tracked tip of a tool held on an item's edge trembles across it, and each crossing
    // restarted the dwell (docs/sci.md, "Leaving an item").
    double leave_margin_fraction = 0.02;
    double still_fraction = 0.03;  // of the width: a tool's tip "still" during a cross hold
    // A frame this long after the tools last touched ends a crossing (a shorter gap is the
    // segmentation losing the contact for a few frames; the gesture hold's dropout
    // tolerance, measured as GestureHold does).
    double part_ms = 200;
    double activation_height = 0.20, activation_width = 0.40;  // fractions of the frame
    std::array<int, kModalityCount> image_counts{};  // images per modality (ct, xray, mri)
    Vec3d box_target_mm{20, 10, 90};
    double box_tolerance_mm = 10;
};

class SciMachine {
public:
    explicit SciMachine(SciParams params = {}) : params_(params) {}
    void configure(int width, int height);
    void step(const SciFrame& f);

    SciState state() const { return state_; }
    const SciMenu& menu() const { return menus_[static_cast<std::size_t>(menu_)]; }
    int highlighted() const { return highlighted_; }           // index in menu(), or -1
    std::string_view event() const { return event_; }          // "" = none this frame
    double dwell_fraction() const { return dwell_fraction_; }  // 0..1 of the tip's dwell
    double activation_fraction() const { return activation_fraction_; }
    bool active() const { return state_ != SciState::kInactive && state_ != SciState::kActivating; }
    float activation_x0() const { return area_x0_; }
    float activation_y0() const { return area_y0_; }
    float activation_x1() const { return area_x1_; }
    SciModality modality() const { return modality_; }
    int image_index() const { return image_; }
    const ImageBox& box() const { return box_; }
    const SutureThread& suture() const { return suture_; }
    bool suture_started() const { return suture_started_; }
    int box_face() const { return box_face_; }  // the face under the tip, or -1
    void set_camera(const hal::SceneCamera& c) { camera_ = c; }
    // The image box's target marker this frame (default SciParams::box_target_mm); a box
    // placed on it moves with it (a target anchored to a tracked region, issue 8).
    void set_box_target(const Vec3d& target_mm) {
        params_.box_target_mm = target_mm;
        box_.stay_on(target_mm);
    }
    const Vec3d& box_target_mm() const { return params_.box_target_mm; }

private:
    void go(SciState s) { state_ = s; }
    void open(MenuId m);
    void deactivate(std::string_view why);
    void click(int item);
    void execute(const SciItem& item);
    void point(const SciFrame& f);
    void functions(const SciFrame& f);
    void track_loop(const SciFrame& f);
    bool cross_held(const SciFrame& f);
    void remember_tools(const SciFrame& f);
    int sectors_travelled() const;  // of the eight, since the select

    SciParams params_;
    SciMenuTable menus_{};
    int width_ = 0, height_ = 0;
    float area_x0_ = 0, area_x1_ = 0, area_y0_ = 0;
    hal::SceneCamera camera_;

    SciState state_ = SciState::kInactive;
    MenuId menu_ = MenuId::kMain;
    std::array<MenuId, 4> parents_{};  // the menus to Return to
    int depth_ = 0;
    int highlighted_ = -1, hover_ = -1;
    hal::Nanos dwell_start_ = 0, last_t_ = 0;
    bool have_last_t_ = false;
    std::string_view event_;
    double dwell_fraction_ = 0, activation_fraction_ = 0;
    bool cross_armed_ = true;
    // The tools' tips when the cross's still hold began (restarted when one moves).
    std::array<std::array<double, 2>, 2> cross_anchor_{};
    int cross_anchors_ = 0;
    bool cross_holding_ = false;
    // A triangle or double triangle was read and the tools have touched since (no frame
    // more than part_ms after a touching one): a cross formed now is a grasp, and so is
    // the one being held.
    bool open_crossing_ = false, cross_is_grasp_ = false;
    hal::Nanos last_touch_ = 0;
    hal::Nanos cross_still_start_ = 0;
    // The tools' tips of the last frames (a ring, the newest at recent_next_ - 1): how far
    // back a cross the gesture stage dates back found them where they are.
    struct RecentTools {
        hal::Nanos t_ns = 0;
        int count = 0;
        std::array<std::array<double, 2>, 2> tips{};
    };
    std::array<RecentTools, 16> recent_{};
    std::size_t recent_next_ = 0, recent_count_ = 0;
    bool rearm_ = false;            // after a click the tip must leave the items first
    bool wheel_highlight_ = false;  // the highlight came from the wheel, not the tip
    hal::Nanos activation_start_ = 0;
    double last_held_ms_ = 0;
    // confirm: the window and the directions the tip went since it opened
    hal::Nanos confirm_start_ = 0;
    int confirm_item_ = -1;
    double loop_x_ = 0, loop_y_ = 0;
    std::uint8_t loop_sectors_ = 0;  // bit k: a step went in direction k x 45 degrees
    // The loop's recent tips (loop_tip): it is followed on their mean over loop_mean_ms.
    struct TipSample {
        hal::Nanos t = 0;
        double x = 0, y = 0;
    };
    static std::optional<TipSample> loop_tip(const SciFrame& f);
    void remember_tip(const TipSample& tip);
    std::array<TipSample, 32> tips_{};  // 240 ms at up to 130 fps
    int tip_count_ = 0, tip_next_ = 0;
    // The item the tip last left and when: the open grasper's hold that began on it
    // selects it (opening the jaws moves the tracked tip back towards the head).
    int left_item_ = -1;
    hal::Nanos left_at_ = 0;
    // functions
    SciModality modality_ = SciModality::kCt;
    int image_ = 0;
    ImageBox box_;
    int box_face_ = -1, box_face_dwelt_ = -1;
    hal::Nanos box_dwell_start_ = 0;
    SutureThread suture_;
    bool suture_started_ = false;
};

}  // namespace endotower::sci
