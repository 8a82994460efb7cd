#include "endotower/sim/scripted_input.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace endotower::sim {

namespace {

constexpr hal::Nanos kNever = std::numeric_limits<hal::Nanos>::max();

// start + n / fps rounded to the ns, the same formula as RecordedFrameSource's capture
// times, so "frame N" fires exactly with frame N. Saturating: an absurd frame index
// fires "never", not in the past.
hal::Nanos frame_time(hal::Nanos start, std::int64_t n, double fps) {
    const double offset = static_cast<double>(n) * 1e9 / fps;
    if (!(offset < 9.0e18)) return kNever;
    hal::Nanos t = 0;
    if (__builtin_add_overflow(start, static_cast<hal::Nanos>(std::llround(offset)), &t)) return kNever;
    return t;
}

}  // namespace

ScriptedInput::ScriptedInput(const Timeline& timeline, const hal::Clock& clock, hal::Nanos start_ns,
                             double fps)
    : clock_(clock) {
    events_.reserve(timeline.entries.size());
    for (const TimelineEntry& e : timeline.entries) {
        if (!e.region.empty()) continue;  // region marks go to the analysis, not the handle
        hal::ControlEvent ev = e.event;
        if (e.anchor == TimelineEntry::Anchor::kFrame) {
            ev.time_ns = frame_time(start_ns, e.frame, fps);
        } else if (__builtin_add_overflow(start_ns, e.offset_ns, &ev.time_ns)) {
            ev.time_ns = kNever;
        }
        events_.push_back(ev);
    }
    // Stable: events at the same time keep their file order (press before release).
    std::stable_sort(events_.begin(), events_.end(),
                     [](const hal::ControlEvent& a, const hal::ControlEvent& b) {
                         return a.time_ns < b.time_ns;
                     });
}

bool ScriptedInput::poll(hal::ControlEvent& out) {
    if (next_ >= events_.size() || events_[next_].time_ns > clock_.now()) return false;
    out = events_[next_++];
    return true;
}

}  // namespace endotower::sim
