#include "endotower/vision/region_marker.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::vision {

namespace {
double distance(Point2 a, Point2 b) {
    return std::hypot(a.x - b.x, a.y - b.y);
}
}  // namespace

void RegionMarker::begin() {
    marking_ = true;
    closed_ready_ = false;
    count_ = 0;
    has_anchor_ = false;
    armed_ = true;
    dwell_progress_ = 0;
}

void RegionMarker::cancel() {
    marking_ = false;
    count_ = 0;
    has_anchor_ = false;
    dwell_progress_ = 0;
}

RegionMarker::Event RegionMarker::close() {
    marking_ = false;
    closed_ready_ = true;
    has_anchor_ = false;
    dwell_progress_ = 0;
    return Event::kClosed;
}

RegionMarker::Event RegionMarker::place(Point2 p) {
    // Back at the first vertex: that closes the outline instead of adding a vertex.
    if (count_ >= 3 && distance(p, vertices_[0]) <= params_.close_px) return close();
    vertices_[count_++] = p;
    last_placed_ = p;
    armed_ = false;
    has_anchor_ = false;
    dwell_progress_ = 0;
    if (count_ == kMaxVertices) {
        close();
    }
    return count_ == kMaxVertices ? Event::kClosed : Event::kVertex;
}

RegionMarker::Event RegionMarker::update(const Point2* tip,
                                         std::span<const hal::ControlEvent> events,
                                         hal::Nanos t_ns) {
    if (!marking_) return Event::kNone;
    for (const hal::ControlEvent& e : events) {
        if (e.button != 0) continue;
        if (e.kind == hal::ControlEvent::Kind::kLongPress) {
            if (count_ >= 3) return close();
            cancel();
            return Event::kCancelled;
        }
        if (e.kind == hal::ControlEvent::Kind::kButtonPress && tip != nullptr) return place(*tip);
    }
    if (tip == nullptr) {
        has_anchor_ = false;
        dwell_progress_ = 0;
        return Event::kNone;
    }
    if (!armed_) {
        if (distance(*tip, last_placed_) <= params_.still_px) return Event::kNone;
        armed_ = true;
    }
    if (!has_anchor_ || distance(*tip, anchor_) > params_.still_px) {
        anchor_ = *tip;
        anchor_ns_ = t_ns;
        has_anchor_ = true;
        dwell_progress_ = 0;
        return Event::kNone;
    }
    const double held_ms = static_cast<double>(t_ns - anchor_ns_) / 1e6;
    dwell_progress_ = std::min(1.0, held_ms / params_.dwell_ms);
    // The vertex goes where the tip settled, not where it drifted to within the tolerance.
    if (held_ms >= params_.dwell_ms) return place(anchor_);
    return Event::kNone;
}

bool RegionMarker::take_polygon(std::array<Point2, kMaxVertices>& out, std::size_t& count) {
    if (!closed_ready_) return false;
    closed_ready_ = false;
    std::copy_n(vertices_.begin(), count_, out.begin());
    count = count_;
    count_ = 0;
    return true;
}

}  // namespace endotower::vision
