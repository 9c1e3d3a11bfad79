#pragma once
// The unit eigenvector of the smallest eigenvalue of many symmetric 3x3 matrices (a scan's
// neighbourhood scatters: its plane normals), eight at a time. Without the trigonometric closed
// form: B = (A - tr(A)/3 I) / s, s = sqrt(tr(B0^2) / 6), has eigenvalues 2 cos(.) in [-2, 2]
// and characteristic x^3 - 3x - det(B) = 0; its smallest root (in [-2, -1]) is reached by Newton
// from -2, then the eigenvector is the largest cross product of two rows of B - x I (they span
// the plane orthogonal to it). The lanes of a block run the same steps (a lane loop under
// `omp simd`, cloned for AVX-512 / AVX2 / SSE2: the two divisions and square roots per matrix
// no longer wait one after the other); the few matrices still moving after
// kBlockNewtonSteps (two nearly equal small eigenvalues) finish one by one. Every lane computes
// exactly what one matrix alone would.
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::registration {

// Symmetric 3x3 matrices by their upper triangle, one coordinate array per entry.
struct SymmetricMatrices {
  std::vector<double> a00, a01, a02, a11, a12, a22;
  void resize(std::size_t n) {
    for (auto* v : {&a00, &a01, &a02, &a11, &a12, &a22}) v->resize(n);
  }
  std::size_t size() const { return a00.size(); }
};

// One unit vector per matrix (its sign arbitrary); UnitX for an isotropic matrix (every
// direction an eigenvector) or a degenerate one.
std::vector<Vec3> smallest_eigenvectors(const SymmetricMatrices& matrices);

// Newton steps on the normalised cubic; it converges from the left, quadratically unless the two
// smallest eigenvalues (nearly) coincide, where the normal is ill-defined anyway, and stops when
// x no longer moves. On the bench's car scans: 4-6 steps for 80-90 % of the points, at most 17;
// 30 is a safeguard that was never reached.
inline constexpr int kMaxNewtonSteps = 30;
// The steps a block's lanes take together: 8 leaves the few points still moving to the scalar
// finish.
inline constexpr int kBlockNewtonSteps = 8;

}  // namespace twistslam::registration
