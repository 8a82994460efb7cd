#include "endotower/eval/assignment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace endotower::eval {

namespace {

// Hungarian method with potentials for n <= m (cost n x m): row i -> column.
std::vector<int> hungarian(const std::vector<double>& a, int n, int m) {
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> u(n + 1, 0), v(m + 1, 0);
    std::vector<int> p(m + 1, 0), way(m + 1, 0);
    for (int i = 1; i <= n; ++i) {
        p[0] = i;
        int j0 = 0;
        std::vector<double> minv(m + 1, inf);
        std::vector<char> used(m + 1, 0);
        do {
            used[j0] = 1;
            const int i0 = p[j0];
            double delta = inf;
            int j1 = 0;
            for (int j = 1; j <= m; ++j) {
                if (used[j]) continue;
                const double cur = a[(i0 - 1) * m + (j - 1)] - u[i0] - v[j];
                if (cur < minv[j]) {
                    minv[j] = cur;
                    way[j] = j0;
                }
                if (minv[j] < delta) {
                    delta = minv[j];
                    j1 = j;
                }
            }
            for (int j = 0; j <= m; ++j) {
                if (used[j]) {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
        } while (p[j0] != 0);
        do {
            const int j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
        } while (j0 != 0);
    }
    std::vector<int> row_to_col(n, -1);
    for (int j = 1; j <= m; ++j)
        if (p[j] != 0) row_to_col[p[j] - 1] = j - 1;
    return row_to_col;
}

}  // namespace

std::vector<int> assign_min_cost(const std::vector<double>& cost, int rows, int cols) {
    if (rows == 0) return {};
    if (cols == 0) return std::vector<int>(rows, -1);
    if (rows <= cols) return hungarian(cost, rows, cols);
    std::vector<double> t(cost.size());
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) t[c * rows + r] = cost[r * cols + c];
    const std::vector<int> col_to_row = hungarian(t, cols, rows);
    std::vector<int> out(rows, -1);
    for (int c = 0; c < cols; ++c) out[col_to_row[c]] = c;
    return out;
}

double mean_of(const std::vector<double>& v) {
    if (v.empty()) return 0;
    double s = 0;
    for (double x : v) s += x;
    return s / static_cast<double>(v.size());
}

double percentile_nearest_rank(std::vector<double> v, double p) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    // p * n first: 95 * 20 / 100 is exactly 19, 0.95 * 20 is not.
    const double rank = std::ceil(p * static_cast<double>(v.size()) / 100.0);
    const auto i = static_cast<std::size_t>(std::clamp(rank, 1.0, static_cast<double>(v.size()))) - 1;
    return v[i];
}

double direction_diff_deg(double a_deg, double b_deg) {
    double d = std::fmod(std::abs(a_deg - b_deg), 360.0);
    return d > 180.0 ? 360.0 - d : d;
}

double line_diff_deg(double a_deg, double b_deg) {
    const double d = direction_diff_deg(a_deg, b_deg);
    return d > 90.0 ? 180.0 - d : d;
}

}  // namespace endotower::eval
