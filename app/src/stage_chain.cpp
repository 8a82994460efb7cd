#include "endotower/app/stage_chain.hpp"

namespace endotower::app {

bool StageChain::add(AnalysisStage* stage) {
    if (stage == nullptr || count_ == kMaxStages) return false;
    stages_[count_++] = stage;
    return true;
}

void StageChain::configure(const hal::FrameFormat& format) {
    for (std::size_t i = 0; i < count_; ++i) stages_[i]->configure(format);
}

void StageChain::process(AnalysisContext& ctx) {
    // One stage's failure is the chain's: the pipeline's fail-safe handles it.
    for (std::size_t i = 0; i < count_; ++i) stages_[i]->process(ctx);
}

}  // namespace endotower::app
