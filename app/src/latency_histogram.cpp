#include "endotower/app/latency_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::app {

void LatencyHistogram::add(hal::Nanos v) {
    if (count_ == 0) min_ = max_ = v;
    min_ = std::min(min_, v);
    max_ = std::max(max_, v);
    ++count_;
    const hal::Nanos bin = std::max<hal::Nanos>(v, 0) / kBin;
    ++bins_[static_cast<std::size_t>(std::min<hal::Nanos>(bin, kBins))];
}

hal::Nanos LatencyHistogram::quantile(double q) const {
    if (count_ == 0) return 0;
    if (q <= 0.0) return min_;
    if (q >= 1.0) return max_;
    const auto rank = static_cast<std::int64_t>(std::ceil(q * static_cast<double>(count_)));
    std::int64_t seen = 0;
    for (std::size_t i = 0; i <= kBins; ++i) {
        seen += bins_[i];
        if (seen >= rank) {
            // The bin's upper edge, but never outside the observed range.
            const hal::Nanos edge = static_cast<hal::Nanos>(i + 1) * kBin - 1;
            return std::clamp(edge, min_, max_);
        }
    }
    return max_;
}

}  // namespace endotower::app
