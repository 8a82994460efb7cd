// ScriptedInput: plays a Timeline as a ControlInput. Entries are resolved to times
// once: "frame N" -> start + N / fps (RecordedFrameSource's capture time of frame N),
// "t S" -> start + S; then handed out in
// time order (file order for equal times) as the clock reaches them.
#pragma once

#include <cstddef>
#include <vector>

#include "endotower/hal/clock.hpp"
#include "endotower/hal/control_input.hpp"
#include "endotower/sim/timeline.hpp"

namespace endotower::sim {

class ScriptedInput final : public hal::ControlInput {
public:
    // Borrows the clock. start_ns is the first frame's capture time.
    ScriptedInput(const Timeline& timeline, const hal::Clock& clock, hal::Nanos start_ns,
                  double fps);

    bool poll(hal::ControlEvent& out) override;
    std::size_t remaining() const { return events_.size() - next_; }

private:
    const hal::Clock& clock_;
    std::vector<hal::ControlEvent> events_;  // sorted by time; allocated once
    std::size_t next_ = 0;
};

}  // namespace endotower::sim
