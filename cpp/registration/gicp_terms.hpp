#pragma once
// GICP's normal equations (gicp.hpp) summed over one linearisation's correspondences, eight
// at a time: the correspondence search (branchy, scalar) collects each pair's vectors into
// coordinate arrays, then the sum runs lane by lane over blocks of eight, which GCC builds for
// AVX-512, AVX2 and baseline x86-64 (target_clones). Each pair's information
// (plane_pair_information: two divisions) and its rank-two part of J^T W J no longer wait one
// after the other on a scalar unit: that latency was 20-30 % of the linearisation in perf.
// Each lane sums its own pairs in order and the lanes are added at the end, so the result is
// deterministic; it differs from a pair-by-pair sum by rounding only.
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::registration {

// One linearisation's correspondences, in the target frame: the moved source point q, the
// residual e = target point - q, the target point's plane normal n and the rotated source
// normal m.
class GicpTerms {
 public:
  // Empties the terms and makes room for `capacity` pairs: add() writes without a check (it
  // runs once per correspondence, every iteration), so at most that many may be added.
  void reset(int capacity);
  void add(const Vec3& q, const Vec3& e, const Vec3& n, const Vec3& m) {
    double* const at[12] = {&columns_[0][size_], &columns_[1][size_], &columns_[2][size_],
                            &columns_[3][size_], &columns_[4][size_], &columns_[5][size_],
                            &columns_[6][size_], &columns_[7][size_], &columns_[8][size_],
                            &columns_[9][size_], &columns_[10][size_], &columns_[11][size_]};
    *at[0] = q[0], *at[1] = q[1], *at[2] = q[2], *at[3] = e[0], *at[4] = e[1], *at[5] = e[2];
    *at[6] = n[0], *at[7] = n[1], *at[8] = n[2], *at[9] = m[0], *at[10] = m[1], *at[11] = m[2];
    ++size_;
  }
  int size() const { return size_; }

  // Pads the arrays to whole blocks (zero pairs, which sum_normal_equations gives no weight)
  // and returns the block count. Called by sum_normal_equations.
  int pad_to_blocks();
  // The coordinate arrays: q (0-2), e (3-5), n (6-8), m (9-11).
  const double* column(int k) const { return columns_[k].data(); }

 private:
  int size_ = 0;
  std::vector<double> columns_[12];
};

struct GicpNormalEquations {
  Mat6 H = Mat6::Zero();   // J^T W J (twist [v; w], target frame, left perturbation)
  Vec6 b = Vec6::Zero();   // J^T W e
  double cost = 0.0;       // sum of the squared Mahalanobis residuals (or their Huber cost)
  double sum_squared_error_m2 = 0.0;  // sum of |e|^2
};

// The pairs per block (one AVX-512 register of doubles).
inline constexpr int kGicpLanes = 8;

// H, b and the costs of `terms` (padded in place). huber: Huber weights with the threshold on
// the Mahalanobis residual (GicpOptions).
GicpNormalEquations sum_normal_equations(GicpTerms& terms, bool huber, double huber_threshold);

}  // namespace twistslam::registration
