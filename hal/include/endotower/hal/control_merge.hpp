// ControlMerge: several ControlInputs (say a GPIO button and a USB HID handle) seen
// as one stream, in timestamp order. Borrows its inputs; they must outlive it.
#pragma once

#include <array>
#include <cstddef>

#include "endotower/hal/control_input.hpp"

namespace endotower::hal {

class ControlMerge final : public ControlInput {
public:
    static constexpr std::size_t kMaxInputs = 8;

    // False when kMaxInputs are already attached.
    bool attach(ControlInput* input);
    std::size_t size() const { return count_; }

    // The oldest of the inputs' pending events (ties: the earlier attached input).
    bool poll(ControlEvent& out) override;

private:
    struct Slot {
        ControlInput* input = nullptr;
        ControlEvent pending{};
        bool has_pending = false;
    };
    std::array<Slot, kMaxInputs> slots_{};
    std::size_t count_ = 0;
};

}  // namespace endotower::hal
