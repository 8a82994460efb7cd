// Optimal one-to-one assignment (Hungarian method, O(n^3)) and the small statistics
// the metrics share.
#pragma once

#include <vector>

namespace endotower::eval {

// cost: rows x cols, row-major. Returns for each row the assigned column, or -1 when
// rows > cols and the row is left over. Minimises the total cost over the pairs.
std::vector<int> assign_min_cost(const std::vector<double>& cost, int rows, int cols);

// Arithmetic mean; 0 for an empty set.
double mean_of(const std::vector<double>& v);
// Nearest-rank percentile: the value at sorted position ceil(p/100 * n) - 1 (p in
// (0, 100]); 0 for an empty set. p95 of {1..20} is 19, of {1..10} is 10.
double percentile_nearest_rank(std::vector<double> v, double p);

// Smallest angle between two directions, degrees in [0, 180].
double direction_diff_deg(double a_deg, double b_deg);
// Smallest angle between two undirected lines, degrees in [0, 90].
double line_diff_deg(double a_deg, double b_deg);

}  // namespace endotower::eval
