#pragma once
// Per-point covariances from the k nearest neighbours, regularised to a plane (Segal et al.,
// "Generalized-ICP", RSS 2009): the sample covariance's eigenvectors are kept and its
// eigenvalues replaced by (1, 1, eps), eps along the normal (the smallest axis).
#include <vector>

#include "geometry/types.hpp"
#include "registration/kdtree.hpp"

namespace twistslam::registration {

// Variance along the normal relative to the in-plane ones (dimensionless). 1e-3 is Segal's
// value, also used by small_gicp, Open3D and PCL: the same cost for every method in the bench.
inline constexpr double kPlaneEpsilon = 1e-3;

// Covariance of every point from its num_neighbors nearest (itself included) in `tree`, which
// was built from `points`. Throws std::invalid_argument unless tree.size() >= num_neighbors
// >= 3. Neighbours that all coincide give an arbitrary (but finite) plane.
std::vector<Mat3> plane_covariances(const std::vector<Vec3>& points, const KdTree& tree,
                                    int num_neighbors, double plane_epsilon = kPlaneEpsilon);

}  // namespace twistslam::registration
