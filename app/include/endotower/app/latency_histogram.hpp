// LatencyHistogram: fixed 10 us bins up to 1 s (plus overflow), for percentiles of
// per-frame latency over runs of any length without allocating per frame.
#pragma once

#include <array>
#include <cstdint>

#include "endotower/hal/time.hpp"

namespace endotower::app {

class LatencyHistogram {
public:
    static constexpr hal::Nanos kBin = 10'000;
    static constexpr std::size_t kBins = 100'000;

    void add(hal::Nanos v);
    std::int64_t count() const { return count_; }
    hal::Nanos min() const { return min_; }
    hal::Nanos max() const { return max_; }
    // Upper edge of the bin holding quantile q (0..1); exact min/max at the ends.
    hal::Nanos quantile(double q) const;

private:
    std::array<std::uint32_t, kBins + 1> bins_{};
    std::int64_t count_ = 0;
    hal::Nanos min_ = 0, max_ = 0;
};

}  // namespace endotower::app
