// Ground truth from the 3-D state of a frame (private): projections through the same
// camera model the renderer uses, occlusion by casting the same rays.
#pragma once

#include "endotower/scene/truth.hpp"
#include "world.hpp"

namespace endotower::scene::detail {

void compute_truth(const SceneModel& model, const FrameWorld& world, int frame, FrameTruth& out);

}  // namespace endotower::scene::detail
