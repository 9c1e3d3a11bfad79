#pragma once
// Minimum-cost one-to-one assignment of a rectangular cost matrix (Hungarian method, with
// row / column potentials and shortest augmenting paths: O(n^2 m) for n <= m).
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace twistslam::objects {

// Pairs (row, col) minimising the total cost among assignments with the largest number of
// allowed pairs; a pair is allowed when its cost is finite and <= max_cost. Forbidden pairs
// are never returned. Empty matrices give no pairs. NaN costs count as forbidden.
std::vector<std::pair<int, int>> solve_assignment(const Eigen::MatrixXd& cost, double max_cost);

}  // namespace twistslam::objects
