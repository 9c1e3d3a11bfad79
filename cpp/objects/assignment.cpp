#include "objects/assignment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twistslam::objects {
namespace {

// Hungarian method for n <= m (rows <= columns), 1-based potentials u, v; returns the
// column of each row. Classic formulation (Kuhn-Munkres with Dijkstra-like augmentation).
std::vector<int> hungarian(const Eigen::MatrixXd& a) {
  const int n = static_cast<int>(a.rows()), m = static_cast<int>(a.cols());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), minv(m + 1);
  std::vector<int> p(m + 1, 0), way(m + 1, 0);
  std::vector<char> used(m + 1);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(minv.begin(), minv.end(), inf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double cur = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (cur < minv[j]) minv[j] = cur, way[j] = j0;
        if (minv[j] < delta) delta = minv[j], j1 = j;
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
    } while (j0);
  }
  std::vector<int> col_of_row(n, -1);
  for (int j = 1; j <= m; ++j) {
    if (p[j]) col_of_row[p[j] - 1] = j - 1;
  }
  return col_of_row;
}

}  // namespace

std::vector<std::pair<int, int>> solve_assignment(const Eigen::MatrixXd& cost, double max_cost) {
  std::vector<std::pair<int, int>> pairs;
  if (cost.rows() == 0 || cost.cols() == 0) return pairs;
  const bool transpose = cost.rows() > cost.cols();
  Eigen::MatrixXd a = transpose ? Eigen::MatrixXd(cost.transpose()) : cost;
  // Allowed costs are shifted to be >= 0 (each row is assigned exactly once, so a constant
  // shift changes every assignment's total alike), then forbidden pairs cost more than any
  // sum of allowed ones: the optimum first maximises the number of allowed pairs, then
  // minimises their cost (as the KITTI devkit's gating does).
  double min_allowed = std::numeric_limits<double>::infinity(), max_allowed = 0;
  int n_allowed = 0;
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    const double c = a.data()[k];
    if (std::isfinite(c) && c <= max_cost) {
      min_allowed = std::min(min_allowed, c);
      max_allowed = std::max(max_allowed, c);
      ++n_allowed;
    }
  }
  if (n_allowed == 0) return pairs;
  const double forbidden = (max_allowed - min_allowed + 1.0) * (std::min(a.rows(), a.cols()) + 1.0);
  Eigen::MatrixXd allowed = Eigen::MatrixXd::Zero(a.rows(), a.cols());
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    double& c = a.data()[k];
    const bool ok = std::isfinite(c) && c <= max_cost;
    allowed.data()[k] = ok;
    c = ok ? c - min_allowed : forbidden;
  }
  const std::vector<int> col_of_row = hungarian(a);
  for (int r = 0; r < static_cast<int>(col_of_row.size()); ++r) {
    const int c = col_of_row[r];
    if (c < 0 || !allowed(r, c)) continue;
    pairs.emplace_back(transpose ? c : r, transpose ? r : c);
  }
  return pairs;
}

}  // namespace twistslam::objects
