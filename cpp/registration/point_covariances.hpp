#pragma once
// Per-point covariances from the k nearest neighbours, regularised to a plane (Segal et al.,
// "Generalized-ICP", RSS 2009): the sample covariance's eigenvectors are kept and its
// eigenvalues replaced by (1, 1, eps), eps along the normal (the smallest axis).
#include <vector>

#include "geometry/types.hpp"
#include "registration/grid_knn.hpp"
#include "registration/kdtree.hpp"

namespace twistslam::registration {

// Variance along the normal relative to the in-plane ones (dimensionless). 1e-3 is Segal's
// value, also used by small_gicp, Open3D and PCL: the same cost for every method in the bench.
inline constexpr double kPlaneEpsilon = 1e-3;

// Unit normal of every point: the smallest-eigenvalue axis of the covariance of its
// num_neighbors nearest (itself included) in `tree`, which was built from `points`. The sign
// is arbitrary (a plane covariance does not see it). Throws std::invalid_argument unless
// tree.size() >= num_neighbors >= 3. Neighbours that all coincide give an arbitrary (but unit)
// normal. With `neighborhoods`, also each point's neighbours: their indices (unordered), at
// [i * num_neighbors, (i + 1) * num_neighbors) of `indices`, and the squared distance to the
// farthest of them in `radius2_m2` (the k-NN search finds them anyway). The neighbours come from
// all_knn (grid_knn.hpp): the KD-tree's k-NN up to ties; with `grid`, its voxel grid is kept.
std::vector<Vec3> plane_normals(const std::vector<Vec3>& points, const KdTree& tree,
                                int num_neighbors, Neighborhoods* neighborhoods = nullptr,
                                PointGrid* grid = nullptr);

// The plane covariance of a unit normal n: V diag(eps, 1, 1) V^T = I - (1 - eps) n n^T (V
// orthonormal with n its first column), so a normal is all GICP needs to store per point.
inline Mat3 plane_covariance(const Vec3& normal, double plane_epsilon = kPlaneEpsilon) {
  return Mat3::Identity() - (1.0 - plane_epsilon) * normal * normal.transpose();
}

// The information (C_n + C_m)^-1 of two plane covariances with unit normals n and m (GICP's
// combined covariance C_t + R C_s R^T, with m = R n_s), in closed form: C = 2 I - a U U^T with
// U = [n m], a = 1 - eps, so by Woodbury W = 0.5 I + alpha_sum u u^T + alpha_diff v v^T with
// u = n + m, v = n - m, alpha_sum = 1 / (8 (eps / a + (1 - c) / 2)), alpha_diff = 1 / (8 (eps /
// a + (1 + c) / 2)), c = n . m (the eigenvalues of the 2x2 Woodbury core along (1, 1) and
// (1, -1), written without the cancellation of 1 / a - 1). No 3x3 inverse, and a sum of
// rank-one terms lets the Gauss-Newton Hessian be accumulated as two 6-vector outer products.
struct PlanePairInformation {
  double alpha_sum = 0.0;   // weight of (n + m)(n + m)^T
  double alpha_diff = 0.0;  // weight of (n - m)(n - m)^T
};
inline PlanePairInformation plane_pair_information(double cos_nm,
                                                   double plane_epsilon = kPlaneEpsilon) {
  const double floor = plane_epsilon / (1.0 - plane_epsilon);
  return {1.0 / (8.0 * (floor + 0.5 * (1.0 - cos_nm))),
          1.0 / (8.0 * (floor + 0.5 * (1.0 + cos_nm)))};
}

// Covariance of every point (plane_covariance of plane_normals); same arguments and errors.
std::vector<Mat3> plane_covariances(const std::vector<Vec3>& points, const KdTree& tree,
                                    int num_neighbors, double plane_epsilon = kPlaneEpsilon);

}  // namespace twistslam::registration
