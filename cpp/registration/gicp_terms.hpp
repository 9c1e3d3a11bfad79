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
  void clear() { size_ = 0; }
  void add(const Vec3& q, const Vec3& e, const Vec3& n, const Vec3& m);
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
