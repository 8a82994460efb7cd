// RegionMarker: the surgeon outlines a tissue region with the tool tip, the tool used
// as a 3-D mouse (issue 7). A pure state machine: no pixels, no allocation.
//
// While marking, a vertex is placed where the tip is
//  - on a press of the handle's button, or
//  - when the tip has stayed within `still_px` of one place for `dwell_ms` (2000, the
//    interface's wait-to-click time); the next dwell needs the tip to leave that place
//    first, so holding still places one vertex, not many.
// With at least 3 vertices, a vertex placed within `close_px` of the first one closes
// the polygon (the surgeon returns to where they began), and so does a long press. A
// long press with fewer than 3 vertices cancels. Marking ends after kMaxVertices
// vertices with the polygon closed.
// Inputs per frame: the tip (nullptr: no tool, the dwell restarts), the handle's
// events since the previous frame, the frame's capture time. take_polygon() hands a
// closed polygon over once.
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include "endotower/hal/control_input.hpp"
#include "endotower/vision/tool_pose.hpp"

namespace endotower::vision {

struct RegionMarkerParams {
    double dwell_ms = 2000.0;
    double still_px = 10.0;
    double close_px = 20.0;
};

class RegionMarker {
public:
    static constexpr std::size_t kMaxVertices = 16;
    enum class Event { kNone, kStarted, kVertex, kClosed, kCancelled };

    explicit RegionMarker(RegionMarkerParams params = {}) : params_(params) {}
    void set_params(const RegionMarkerParams& params) { params_ = params; }
    // Starts a new outline (forgetting an unfinished one).
    void begin();
    void cancel();
    bool marking() const { return marking_; }

    // One frame: returns what happened (at most one vertex per frame).
    Event update(const Point2* tip, std::span<const hal::ControlEvent> events, hal::Nanos t_ns);

    std::span<const Point2> vertices() const { return {vertices_.data(), count_}; }
    // 0..1 of the dwell towards the next vertex (for the cursor's progress ring).
    double dwell_progress() const { return dwell_progress_; }
    // The closed polygon, once: true and fills `out` after kClosed.
    bool take_polygon(std::array<Point2, kMaxVertices>& out, std::size_t& count);

private:
    Event place(Point2 p);
    Event close();

    RegionMarkerParams params_;
    bool marking_ = false, closed_ready_ = false;
    std::array<Point2, kMaxVertices> vertices_{};
    std::size_t count_ = 0;
    // The dwell: where the tip settled, since when; `armed` false until it leaves the
    // place of the last vertex.
    Point2 anchor_;
    hal::Nanos anchor_ns_ = 0;
    bool has_anchor_ = false, armed_ = true;
    Point2 last_placed_;
    double dwell_progress_ = 0;
};

}  // namespace endotower::vision
