// StageChain: several analysis stages run in order on the same frame, drawing on the
// same overlay and writing their own trace members (e.g. the status badge, then the
// tool tracker). Borrows its stages. Up to kMaxStages.
#pragma once

#include <array>
#include <cstddef>

#include "endotower/app/analysis_stage.hpp"

namespace endotower::app {

class StageChain final : public AnalysisStage {
public:
    static constexpr std::size_t kMaxStages = 8;
    bool add(AnalysisStage* stage);
    std::size_t size() const { return count_; }

    std::string_view name() const override { return "chain"; }
    void configure(const hal::FrameFormat& format) override;
    void process(AnalysisContext& ctx) override;

private:
    std::array<AnalysisStage*, kMaxStages> stages_{};
    std::size_t count_ = 0;
};

}  // namespace endotower::app
