// ControlInput: the tool handle's button and scroll wheel (GPIO, USB HID, or a
// scripted timeline in simulation), as timestamped events.
#pragma once

#include <cstdint>
#include <string_view>

#include "endotower/hal/time.hpp"

namespace endotower::hal {

struct ControlEvent {
    // kLongPress: the button has been held for the long-press time; sent once while
    // it is still down (its release follows as usual).
    enum class Kind : std::uint8_t { kButtonPress, kButtonRelease, kWheel, kLongPress };
    Kind kind = Kind::kButtonPress;
    std::uint8_t button = 0;  // which button, 0 = the handle's main button
    std::int16_t delta = 0;   // wheel detents, positive = away from the surgeon
    Nanos time_ns = 0;        // when it happened, same clock as frame timestamps
};

std::string_view to_string(ControlEvent::Kind k);

class ControlInput {
public:
    virtual ~ControlInput() = default;

    // Takes the oldest pending event with time_ns <= now. Never blocks, never
    // allocates; false when there is none. Called from the pipeline's thread.
    virtual bool poll(ControlEvent& out) = 0;
};

}  // namespace endotower::hal
