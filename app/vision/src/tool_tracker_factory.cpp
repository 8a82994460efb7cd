#include "endotower/vision/tool_tracker_factory.hpp"

#include <algorithm>
#include <array>

#include "endotower/vision/ekf_tool_tracker.hpp"
#include "endotower/vision/hybrid_tool_tracker.hpp"
#include "endotower/vision/mhi_tool_tracker.hpp"
#include "endotower/vision/mog2_tool_tracker.hpp"
#include "endotower/vision/particle_tool_tracker.hpp"

namespace endotower::vision {

namespace {
constexpr std::array<std::string_view, 6> kNames{"ekf",    "mog2", "particle", "particle_sorted",
                                                 "hybrid", "mhi"};
}  // namespace

std::span<const std::string_view> book_tracker_names() {
    return kNames;
}

bool is_book_tracker(std::string_view name) {
    return std::find(kNames.begin(), kNames.end(), name) != kNames.end();
}

std::unique_ptr<ToolTracker> make_book_tracker(std::string_view name) {
    if (name == "ekf") return std::make_unique<EkfToolTracker>();
    if (name == "mog2") return std::make_unique<Mog2ToolTracker>();
    if (name == "mhi") return std::make_unique<MhiToolTracker>();
    if (name == "particle") return std::make_unique<ParticleToolTracker>();
    if (name == "particle_sorted")
        return std::make_unique<ParticleToolTracker>(
            ParticleToolTrackerParams{.sorted_resampling = true});
    if (name == "hybrid") return std::make_unique<HybridToolTracker>();
    return nullptr;
}

}  // namespace endotower::vision
