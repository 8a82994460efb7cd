#include "endotower/vision/particle_resampling.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace endotower::vision {

double effective_sample_size(std::span<const double> weights) {
    double sq = 0;
    for (double w : weights) sq += w * w;
    return sq > 0 ? 1.0 / sq : 0.0;
}

void sorted_resampling(std::span<const double> weights, std::span<int> order,
                       std::span<int> source) {
    const int n = static_cast<int>(source.size());
    std::iota(order.begin(), order.end(), 0);
    // Stable: equal weights keep their order, as in the book's example.
    std::stable_sort(order.begin(), order.end(), [&weights](int a, int b) {
        return weights[static_cast<std::size_t>(a)] > weights[static_cast<std::size_t>(b)];
    });
    int k = 0;
    for (std::size_t j = 0; j < order.size() && k < n; ++j) {
        const int copies = std::max(
            1, static_cast<int>(std::ceil(weights[static_cast<std::size_t>(order[j])] * n - 1e-9)));
        for (int c = 0; c < copies && k < n; ++c) source[static_cast<std::size_t>(k++)] = order[j];
    }
}

void systematic_resampling(std::span<const double> weights, double u, std::span<int> source) {
    const std::size_t n = source.size();
    const double step = 1.0 / static_cast<double>(n);
    double c = weights[0];
    std::size_t j = 0;
    for (std::size_t k = 0; k < n; ++k, u += step) {
        while (u > c && j + 1 < weights.size()) c += weights[++j];
        source[k] = static_cast<int>(j);
    }
}

}  // namespace endotower::vision
