// ToolTracker: finds the laparoscopic tools in a frame. One implementation per
// method of the book (and ours), selectable by name in the board file.
//
// Output per tool, in the coordinates of the frame as given (x right, y down):
// the extreme tip, the head (where the shaft's straight edges end), the shaft's
// direction from the tip towards the incision (atan2(dy, dx), degrees), the two
// edges, a confidence in 0..1 (0: not found). Identities are kept frame to frame.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>

#include "endotower/hal/frame.hpp"
#include "endotower/vision/edge_pairing.hpp"

namespace endotower::vision {

struct ToolEstimate {
    int id = 0;
    bool present = false;
    Point2 tip, head;
    double axis_deg = 0;
    double width_px = 0;
    double confidence = 0;
    EdgePair edges;
};

class ToolTracker {
public:
    static constexpr std::size_t kMaxTools = 2;
    virtual ~ToolTracker() = default;
    virtual std::string_view name() const = 0;
    // Off the per-frame path, for every new format.
    virtual void configure(const hal::FrameFormat& format) = 0;
    // Fills out[0..n) and returns n (<= kMaxTools); tools not found are not listed.
    virtual std::size_t track(const hal::Frame& frame, std::span<ToolEstimate, kMaxTools> out) = 0;
};

}  // namespace endotower::vision
