#include "endotower/sci/sci_machine.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace endotower::sci {

namespace {

hal::Nanos ms_to_ns(double ms) {
    return static_cast<hal::Nanos>(std::llround(ms * 1e6));
}

// A frame's tool tips, and whether every one of `n` tips lies within `still_px` of one
// of the `na` anchors (a tool the tracker drops, crossed shafts merging, is no motion).
using Tips = std::array<std::array<double, 2>, 2>;
bool tips_near(const Tips& tips, int n, const Tips& anchor, int na, double still_px) {
    for (int i = 0; i < n; ++i) {
        const auto& t = tips[static_cast<std::size_t>(i)];
        bool near = false;
        for (int k = 0; k < na; ++k) {
            const auto& a = anchor[static_cast<std::size_t>(k)];
            near = near || std::hypot(t[0] - a[0], t[1] - a[1]) <= still_px;
        }
        if (!near) return false;
    }
    return true;
}

int tips_of(const SciFrame& f, Tips& tips) {
    for (int i = 0; i < f.tool_count; ++i)
        tips[static_cast<std::size_t>(i)] = {f.tools[static_cast<std::size_t>(i)].x,
                                             f.tools[static_cast<std::size_t>(i)].y};
    return f.tool_count;
}

}  // namespace

std::string_view to_string(SciState s) {
    switch (s) {
        case SciState::kInactive:
            return "inactive";
        case SciState::kActivating:
            return "activating";
        case SciState::kMenu:
            return "menu";
        case SciState::kHighlight:
            return "highlight";
        case SciState::kConfirm:
            return "confirm";
        case SciState::kGrabbed:
            return "grabbed";
    }
    return "?";
}

void SciMachine::configure(int width, int height) {
    width_ = width, height_ = height;
    menus_ = build_menus(params_.layout, width, height);
    // Fig. 3.31: a band at the bottom of the image, in the middle.
    area_x0_ = static_cast<float>(width * (0.5 - params_.activation_width / 2));
    area_x1_ = static_cast<float>(width * (0.5 + params_.activation_width / 2));
    area_y0_ = static_cast<float>(height * (1.0 - params_.activation_height));
}

void SciMachine::open(MenuId m) {
    menu_ = m;
    highlighted_ = hover_ = left_item_ = -1;
    rearm_ = true;
    wheel_highlight_ = false;
    go(SciState::kMenu);
}

void SciMachine::deactivate(std::string_view why) {
    event_ = why;
    depth_ = 0;
    menu_ = MenuId::kMain;
    highlighted_ = hover_ = left_item_ = -1;
    box_.release();
    go(SciState::kInactive);
}

void SciMachine::click(int item) {
    event_ = "click";
    left_item_ = -1;
    execute(menu().items[static_cast<std::size_t>(item)]);
}

void SciMachine::execute(const SciItem& item) {
    auto push = [this](MenuId m) {
        if (depth_ < static_cast<int>(parents_.size())) parents_[depth_++] = menu_;
        open(m);
    };
    const int n = params_.image_counts[static_cast<std::size_t>(modality_)];
    switch (item.action) {
        case SciAction::kSubmenu:
            push(item.target);
            break;
        case SciAction::kReturn:
            open(depth_ > 0 ? parents_[--depth_] : MenuId::kMain);
            break;
        case SciAction::kMain:
            depth_ = 0, open(MenuId::kMain);
            break;
        case SciAction::kExit:
            deactivate("exit");
            break;
        case SciAction::kView:
            modality_ = item.modality;
            image_ = 0;
            push(MenuId::kViewer);
            break;
        case SciAction::kPrevious:
            if (n > 0) image_ = (image_ + n - 1) % n;
            rearm_ = true;  // a second previous needs the tip to come back
            break;
        case SciAction::kNext:
            if (n > 0) image_ = (image_ + 1) % n;
            rearm_ = true;
            break;
        case SciAction::kPatientRecord:
            push(MenuId::kRecord);
            break;
        case SciAction::kImageBox:
            box_.reset();
            box_face_ = box_face_dwelt_ = -1;
            push(MenuId::kBox);
            break;
        case SciAction::kSuture:
            suture_started_ = false;
            push(MenuId::kSuture);
            break;
    }
}

void SciMachine::point(const SciFrame& f) {
    const auto x = static_cast<float>(f.tools[0].x), y = static_cast<float>(f.tools[0].y);
    int hover = f.tool_count > 0 ? menu().hit(x, y) : -1;
    // The item the tip is on stays until the tip is the margin outside it.
    const auto margin = static_cast<float>(params_.leave_margin_fraction * width_);
    if (!rearm_ && hover_ >= 0 && hover != hover_ && f.tool_count > 0 &&
        menu().near(static_cast<std::size_t>(hover_), x, y, margin))
        hover = hover_;
    if (rearm_) {
        if (hover >= 0) {
            hover_ = -1;
        } else {
            rearm_ = false;
        }
    }
    if (!rearm_ && hover != hover_) {
        hover_ = hover;
        if (hover >= 0) {
            highlighted_ = hover;
            wheel_highlight_ = false;
            dwell_start_ = f.t_ns;
            event_ = "highlight";
        } else if (!wheel_highlight_ && highlighted_ >= 0) {
            left_item_ = highlighted_;
            left_at_ = f.t_ns;
            highlighted_ = -1;
            event_ = "unhighlight";
        }
    }
    if (!rearm_ && hover_ >= 0 && highlighted_ == hover_) {
        const hal::Nanos dwell = ms_to_ns(params_.dwell_ms), held = f.t_ns - dwell_start_;
        dwell_fraction_ =
            dwell > 0 ? std::min(1.0, static_cast<double>(held) / static_cast<double>(dwell)) : 1.0;
        if (held >= dwell) {
            dwell_fraction_ = 0;
            click(hover_);
            return;
        }
    }
    // Open grasper held (the gesture fired): select, then wait for the loop (fig. 3.32).
    // The item is the one under the jaws' tip (the gesture's region): the tracked tip of
    // open jaws can sit 40-60 px back along the shaft, on no item or on the next one
    // (docs/sci.md, "The select on the jaws' tip"); a highlight the wheel chose stays.
    // Else the one under the tip, or the one the tip left while the grasper was held
    // still: the hold began on it. Opening the jaws moves the tracked tip, and the hold
    // dates from the first frame read as an open grasper, up to the gesture hold's
    // dropout tolerance later: an item left within `select_grace_ms` before the hold
    // counts too.
    const bool fired = f.gesture == SciGesture::kOpenGrasper && f.gesture_fired;
    const int jaws_item =
        fired && !rearm_ && !wheel_highlight_
            ? menu().hit(static_cast<float>(f.gesture_x), static_cast<float>(f.gesture_y), margin)
            : -1;
    const bool left_in_hold =
        left_item_ >= 0 && !rearm_ &&
        f.t_ns - left_at_ <= ms_to_ns(f.gesture_held_ms + params_.select_grace_ms);
    const int selected = jaws_item >= 0      ? jaws_item
                         : highlighted_ >= 0 ? highlighted_
                         : left_in_hold      ? left_item_
                                             : -1;
    if (selected >= 0 && fired) {
        highlighted_ = confirm_item_ = selected;
        left_item_ = -1;
        confirm_start_ = f.t_ns;
        loop_sectors_ = 0;
        tip_count_ = tip_next_ = 0;  // the loop's path starts here
        loop_x_ = loop_y_ = 0;
        if (const auto tip = loop_tip(f)) {
            loop_x_ = tip->x, loop_y_ = tip->y;
            remember_tip(*tip);
        }
        event_ = "select";
        go(SciState::kConfirm);
        return;
    }
    go(highlighted_ >= 0 ? SciState::kHighlight : SciState::kMenu);
}

// The loop is made by the jaws that selected: while a gesture is read, its region's
// tip (the end of the open jaws, or where the held gesture was last seen). The tracked
// tip of open jaws slides along the shaft by 40-60 px from frame to frame (a straight
// stroke read so went in 5-7 directions: docs/sci.md, "The loop on the jaws' tip");
// without a gesture, the tracked tip.
std::optional<SciMachine::TipSample> SciMachine::loop_tip(const SciFrame& f) {
    if (f.gesture != SciGesture::kNone) return TipSample{f.t_ns, f.gesture_x, f.gesture_y};
    if (f.tool_count > 0) return TipSample{f.t_ns, f.tools[0].x, f.tools[0].y};
    return std::nullopt;
}

void SciMachine::remember_tip(const TipSample& tip) {
    tips_[static_cast<std::size_t>(tip_next_)] = tip;
    tip_next_ = (tip_next_ + 1) % static_cast<int>(tips_.size());
    tip_count_ = std::min(tip_count_ + 1, static_cast<int>(tips_.size()));
}

void SciMachine::track_loop(const SciFrame& f) {
    const auto tip = loop_tip(f);
    if (!tip) return;
    remember_tip(*tip);
    // The loop is read on the tip's mean over the last `loop_mean_ms`: the jaws' tip
    // jumps between the two jaws' ends, the tracked tip along the shaft, by more than the
    // jitter floor, and each jump turns the heading by about 180 degrees. A loop takes
    // about a second; 240 ms shrinks it little.
    const hal::Nanos window = ms_to_ns(params_.loop_mean_ms);
    double sx = 0, sy = 0;
    int n = 0;
    for (int k = 0; k < tip_count_; ++k) {
        const TipSample& s = tips_[static_cast<std::size_t>(k)];
        if (f.t_ns - s.t >= window) continue;
        sx += s.x, sy += s.y, ++n;
    }
    const double x = sx / n, y = sy / n;
    const double dx = x - loop_x_, dy = y - loop_y_;
    // Steps of the mean shorter than `loop_step_fraction` of the height are jitter.
    if (std::hypot(dx, dy) < params_.loop_step_fraction * height_) return;
    // A loop travels every direction; a stroke and back two opposite ones, and jitter
    // that passes the floor a few more. The directions travelled, in 45-degree sectors.
    const double heading = std::atan2(dy, dx) * 180.0 / 3.14159265358979323846;
    const int sector = static_cast<int>((heading < 0 ? heading + 360.0 : heading) / 45.0) % 8;
    loop_sectors_ = static_cast<std::uint8_t>(loop_sectors_ | (1u << sector));
    loop_x_ = x, loop_y_ = y;
}

int SciMachine::sectors_travelled() const {
    return std::popcount(static_cast<unsigned>(loop_sectors_));
}

void SciMachine::functions(const SciFrame& f) {
    const double dt = have_last_t_ ? static_cast<double>(f.t_ns - last_t_) / 1e9 : 0.0;
    if (menu_ == MenuId::kSuture && f.tool_count >= 2) {
        // Millimetres with two 3-D tips, else pixels (drawn flat on the image).
        const bool mm = f.tools[0].has_3d && f.tools[1].has_3d && camera_.valid();
        const Vec3d a = mm ? f.tools[0].tip_mm : Vec3d{f.tools[0].x, f.tools[0].y, 0};
        const Vec3d b = mm ? f.tools[1].tip_mm : Vec3d{f.tools[1].x, f.tools[1].y, 0};
        if (!suture_started_)
            suture_.reset(a, b);
        else
            suture_.step(a, b, dt);
        suture_started_ = true;
    }
    if (menu_ != MenuId::kBox) return;
    if (state_ == SciState::kGrabbed) {
        if (f.tool_count > 0 && f.tools[0].has_3d)
            box_.follow(f.tools[0].tip_mm, f.tools[0].axis_dir);
        return;
    }
    // A face is grabbed by a dwell on it, like a button (fig. 4.36a); it needs the 3-D tip.
    box_face_ =
        hover_ < 0 && f.tool_count > 0 ? box_.face_under(f.tools[0].x, f.tools[0].y, camera_) : -1;
    if (box_face_ != box_face_dwelt_) {
        box_face_dwelt_ = box_face_;
        box_dwell_start_ = f.t_ns;
    }
    if (box_face_ >= 0 && f.tools[0].has_3d) {
        const hal::Nanos held = f.t_ns - box_dwell_start_, dwell = ms_to_ns(params_.dwell_ms);
        dwell_fraction_ = std::min(1.0, static_cast<double>(held) / static_cast<double>(dwell));
        if (held >= dwell) {
            box_.grab(f.tools[0].tip_mm, f.tools[0].axis_dir);
            box_face_dwelt_ = -1;
            event_ = "grab";
            go(SciState::kGrabbed);
        }
    }
}

void SciMachine::remember_tools(const SciFrame& f) {
    RecentTools& r = recent_[recent_next_];
    r.t_ns = f.t_ns;
    r.count = tips_of(f, r.tips);
    recent_next_ = (recent_next_ + 1) % recent_.size();
    recent_count_ = std::min(recent_count_ + 1, recent_.size());
}

bool SciMachine::cross_held(const SciFrame& f) {
    // A triangle or double triangle whose open jaws close over the other tool turns into
    // a cross without the tools parting: a grasp, not a command (docs/sci.md, "A cross
    // formed by a grasp"). Contact lost is the segmentation's until a frame comes more
    // than part_ms after the last touching one (GestureHold's dropout measure).
    if (f.tools_touching)
        last_touch_ = f.t_ns;
    else if (f.t_ns - last_touch_ > ms_to_ns(params_.part_ms))
        open_crossing_ = false;
    if (f.gesture == SciGesture::kOpenCrossing) open_crossing_ = true;

    const double still_px = params_.still_fraction * width_;
    const bool formed =
        f.gesture == SciGesture::kCross && (!cross_holding_ || f.gesture_held_ms < last_held_ms_);
    Tips now{};
    const int n = tips_of(f, now);
    // Every tool seen must be near where one was when the hold began.
    const bool restart = f.gesture != SciGesture::kCross || formed ||
                         !tips_near(now, n, cross_anchor_, cross_anchors_, still_px);
    if (restart) {
        cross_holding_ = f.gesture == SciGesture::kCross;
        if (formed) cross_is_grasp_ = open_crossing_;
        cross_anchor_ = now, cross_anchors_ = n;
        // One restarted by a tool's motion holds from now. A cross just formed dates from
        // the gesture's own hold (it may date a few frames back, GestureHold), but only as
        // far back as the tools were where they are now: in those frames they may still
        // have been coming together while another gesture was read (docs/sci.md, "A cross
        // dated back").
        cross_still_start_ = f.t_ns;
        const hal::Nanos since = f.t_ns - ms_to_ns(f.gesture_held_ms);
        for (std::size_t k = 1; formed && k < recent_count_; ++k) {
            const RecentTools& r =
                recent_[(recent_next_ + recent_.size() - 1 - k) % recent_.size()];
            if (r.t_ns < since || !tips_near(r.tips, r.count, now, n, still_px)) break;
            cross_still_start_ = r.t_ns;
        }
    }
    // It opens on a frame that shows the cross, not inside a dropout: tools that have
    // parted leave the cross held for up to 200 ms more (docs/sci.md, "On a frame that
    // shows it").
    return cross_holding_ && !cross_is_grasp_ && !f.gesture_dropout &&
           f.gesture_held_ms >= params_.cross_hold_ms &&
           f.t_ns - cross_still_start_ >= ms_to_ns(params_.cross_hold_ms);
}

void SciMachine::step(const SciFrame& f) {
    event_ = {};
    dwell_fraction_ = activation_fraction_ = 0;
    if (f.gesture != SciGesture::kCross) cross_armed_ = true;

    for (const hal::ControlEvent& e : f.events) {
        if (e.kind == hal::ControlEvent::Kind::kButtonPress && e.button == 0) {
            if (!active()) {
                depth_ = 0;
                open(MenuId::kMain);
                event_ = "activate_button";
            } else if (state_ == SciState::kGrabbed) {
                event_ = box_.place(params_.box_target_mm, params_.box_tolerance_mm) ? "place"
                                                                                     : "release";
                go(SciState::kMenu);
            } else if (state_ != SciState::kConfirm && highlighted_ >= 0) {
                click(highlighted_);
            }
        } else if (e.kind == hal::ControlEvent::Kind::kLongPress && active()) {
            deactivate("deactivate");
        } else if (e.kind == hal::ControlEvent::Kind::kWheel && e.delta != 0 &&
                   (state_ == SciState::kMenu || state_ == SciState::kHighlight)) {
            const int n = menu_ == MenuId::kViewer
                              ? params_.image_counts[static_cast<std::size_t>(modality_)]
                              : static_cast<int>(menu().count);
            if (n == 0) continue;
            if (menu_ == MenuId::kViewer) {
                image_ = ((image_ + e.delta) % n + n) % n;
                event_ = "image";
            } else {
                highlighted_ = highlighted_ < 0 ? (e.delta > 0 ? e.delta - 1 : n + e.delta)
                                                : highlighted_ + e.delta;
                highlighted_ = (highlighted_ % n + n) % n;
                wheel_highlight_ = true;
                event_ = "wheel";
                go(SciState::kHighlight);
            }
        }
    }

    // A cross held still (fig. 3.34a): the quadrant menu when inactive, else off.
    remember_tools(f);
    if (cross_held(f) && cross_armed_) {
        cross_armed_ = false;
        if (active()) {
            deactivate("deactivate");
        } else {
            depth_ = 0;
            open(MenuId::kQuadrant);
            event_ = "quadrant";
        }
    }

    switch (state_) {
        case SciState::kInactive:
        case SciState::kActivating: {
            const bool in_area = f.gesture == SciGesture::kScissors && f.gesture_x >= area_x0_ &&
                                 f.gesture_x < area_x1_ && f.gesture_y >= area_y0_;
            if (!in_area) {
                if (state_ == SciState::kActivating) event_ = "activation_cancel";
                go(SciState::kInactive);
                break;
            }
            // Moving restarts the gesture's hold; so does it restart the activation.
            if (state_ == SciState::kInactive || f.gesture_held_ms < last_held_ms_) {
                activation_start_ = f.t_ns;
                if (state_ == SciState::kInactive) event_ = "activation_start";
                go(SciState::kActivating);
            }
            const hal::Nanos held = f.t_ns - activation_start_,
                             need = ms_to_ns(params_.activation_hold_ms);
            activation_fraction_ =
                std::min(1.0, static_cast<double>(held) / static_cast<double>(need));
            if (held >= need && !f.gesture_dropout) {  // as the cross: a frame that shows it
                depth_ = 0;
                open(MenuId::kMain);
                event_ = "activate_hold";
            }
            break;
        }
        case SciState::kMenu:
        case SciState::kHighlight:
            point(f);
            break;
        case SciState::kConfirm:
            track_loop(f);
            if (sectors_travelled() >= params_.loop_sectors) {
                const int item = confirm_item_;
                go(SciState::kMenu);
                execute(menu().items[static_cast<std::size_t>(item)]);
                if (event_ != "exit") event_ = "confirm";
            } else if (f.t_ns - confirm_start_ >= ms_to_ns(params_.confirm_ms)) {
                // Denied: the tip must leave the item before it can be chosen again.
                event_ = "deny";
                highlighted_ = hover_ = left_item_ = -1;
                rearm_ = true;
                go(SciState::kMenu);
            }
            break;
        case SciState::kGrabbed:
            break;
    }
    if (active()) functions(f);
    last_held_ms_ = f.gesture_held_ms;
    last_t_ = f.t_ns;
    have_last_t_ = true;
}

}  // namespace endotower::sci
