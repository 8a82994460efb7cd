// Particle resampling for the colour particle filter (book ch. 5):
//  - effective_sample_size: N_eff = 1 / sum w^2 (eq. 5.12), weights normalised;
//  - sorted_resampling: the book's weight-sorted strategy (eq. 5.13-5.14): particles
//    in descending weight order, each copied ceil(w N) times, until N are chosen;
//  - systematic_resampling: one uniform offset u in [0, 1/N), then u + k/N.
// Outputs `source[k]`, the index of the old particle that new particle k copies;
// `order` (same size) is scratch. No allocation.
#pragma once

#include <span>

namespace endotower::vision {

double effective_sample_size(std::span<const double> weights);
void sorted_resampling(std::span<const double> weights, std::span<int> order,
                       std::span<int> source);
void systematic_resampling(std::span<const double> weights, double u, std::span<int> source);

}  // namespace endotower::vision
