// ButtonDebouncer: turns a button's raw edges (level after each kernel edge event,
// with the kernel's timestamp) into press / release / long-press events. Pure code.
//
// A level counts once it has held for debounce_ns (default 20 ms) after its last
// edge; shorter excursions are bounces or glitches and produce nothing. A press or
// release is stamped with the FIRST edge of the excursion that led to it (when the
// contact was made or broken), so the bounce does not delay the timestamp, only the
// decision. A long press is stamped press + long_press_ns (0 = never) and comes
// before a release stamped later. Events come out in time order.
#pragma once

#include <cstdint>

#include "endotower/hal/control_input.hpp"

namespace endotower::gpio {

struct DebounceParams {
    hal::Nanos debounce_ns = 20 * hal::kMillisecond;
    hal::Nanos long_press_ns = 800 * hal::kMillisecond;  // 0 = no long press
    std::uint8_t button = 0;                             // ControlEvent::button
};

class ButtonDebouncer {
public:
    // initial_active: the level read when the line was requested (no event for it).
    ButtonDebouncer(DebounceParams params, bool initial_active);

    // The raw level (true = active/pressed) right after an edge at time t.
    void edge(bool active, hal::Nanos t);
    // The next event decided by `now`, if any.
    bool next(hal::Nanos now, hal::ControlEvent& out);
    // When next() can next produce an event without a new edge; -1 = not before an edge.
    hal::Nanos deadline() const;

    bool pressed() const { return stable_; }
    std::uint64_t glitches() const { return glitches_; }  // excursions that did not hold

private:
    hal::Nanos long_press_time() const;
    DebounceParams p_;
    bool stable_ = false;     // debounced level
    bool raw_ = false;        // level after the last edge
    bool excursion_ = false;  // raw has left the stable level since first_edge_
    bool long_sent_ = false;
    hal::Nanos first_edge_ = 0, last_edge_ = 0, press_time_ = 0;
    std::uint64_t glitches_ = 0;
};

}  // namespace endotower::gpio
