// The book's further trackers by their board-file names (analysis.tracker):
//   ekf              EkfToolTracker (eq. 4.17-4.21, fig. 4.16)
//   mog2             Mog2ToolTracker (appendix III, fig. 4.17-4.18)
//   particle         ParticleToolTracker (eq. 5.5-5.12), initialised from the MHI
//   particle_sorted  the same with the weight-sorted resampling (eq. 5.13-5.14)
//   hybrid           HybridToolTracker (fig. 5.5): particle filter + MOG2 + edges/tip
//   mhi              MhiToolTracker (fig. 4.1-4.6)
// (kalman, kalman_red and likelihood are built by the firmware: they take a model or
// their own parameters.) make_book_tracker returns nullptr for any other name; the
// caller owns the result.
#pragma once

#include <memory>
#include <span>
#include <string_view>

#include "endotower/vision/tool_tracker.hpp"

namespace endotower::vision {

std::span<const std::string_view> book_tracker_names();
bool is_book_tracker(std::string_view name);
std::unique_ptr<ToolTracker> make_book_tracker(std::string_view name);

}  // namespace endotower::vision
