#include "endotower/gpio/debouncer.hpp"

namespace endotower::gpio {

using Kind = hal::ControlEvent::Kind;

ButtonDebouncer::ButtonDebouncer(DebounceParams params, bool initial_active)
    : p_(params), stable_(initial_active), raw_(initial_active), long_sent_(initial_active) {}

void ButtonDebouncer::edge(bool active, hal::Nanos t) {
    if (!excursion_ && active != stable_) {
        excursion_ = true;
        first_edge_ = t;
    }
    raw_ = active;
    last_edge_ = t;
}

hal::Nanos ButtonDebouncer::long_press_time() const {
    if (!stable_ || long_sent_ || p_.long_press_ns <= 0) return -1;
    return press_time_ + p_.long_press_ns;
}

bool ButtonDebouncer::next(hal::Nanos now, hal::ControlEvent& out) {
    const hal::Nanos lp = long_press_time();
    // A long press due before the current excursion began is certain already.
    if (lp >= 0 && lp <= now && (!excursion_ || lp < first_edge_)) {
        long_sent_ = true;
        out = {Kind::kLongPress, p_.button, 0, lp};
        return true;
    }
    if (!excursion_ || now - last_edge_ < p_.debounce_ns) return false;
    excursion_ = false;
    if (raw_ == stable_) {
        ++glitches_;            // left and came back within the debounce time
        return next(now, out);  // a long press it held back may be due
    }
    stable_ = raw_;
    if (stable_) {
        press_time_ = first_edge_;
        long_sent_ = false;
    }
    out = {stable_ ? Kind::kButtonPress : Kind::kButtonRelease, p_.button, 0, first_edge_};
    return true;
}

hal::Nanos ButtonDebouncer::deadline() const {
    const hal::Nanos lp = long_press_time();
    if (excursion_) {
        const hal::Nanos settle = last_edge_ + p_.debounce_ns;
        return lp >= 0 && lp < first_edge_ && lp < settle ? lp : settle;
    }
    return lp;
}

}  // namespace endotower::gpio
