#include "registration/point_covariances.hpp"

#include <stdexcept>

namespace twistslam::registration {

std::vector<Mat3> plane_covariances(const std::vector<Vec3>& points, const KdTree& tree,
                                    int num_neighbors, double plane_epsilon) {
  if (num_neighbors < 3 || tree.size() < num_neighbors)
    throw std::invalid_argument("plane_covariances: need num_neighbors >= 3 and at least "
                                "num_neighbors points");
  std::vector<Mat3> covariances(points.size());
  std::vector<Neighbor> neighbors;
  const Vec3 plane_eigenvalues(plane_epsilon, 1.0, 1.0);  // ascending, as the solver returns
  for (const int i : tree.leaf_order()) {
    tree.knn(points[i], num_neighbors, &neighbors);
    Vec3 mean = Vec3::Zero();
    for (const Neighbor& n : neighbors) mean += points[n.index];
    mean /= static_cast<double>(neighbors.size());
    Mat3 scatter = Mat3::Zero();
    for (const Neighbor& n : neighbors) {
      const Vec3 d = points[n.index] - mean;
      scatter.noalias() += d * d.transpose();
    }
    // Closed-form 3x3 eigen decomposition: several times faster than the iterative one and
    // accurate enough for a direction (the eigenvalues are replaced anyway).
    Eigen::SelfAdjointEigenSolver<Mat3> eig;
    eig.computeDirect(scatter);
    const Mat3& V = eig.eigenvectors();
    covariances[i] = V * plane_eigenvalues.asDiagonal() * V.transpose();
  }
  return covariances;
}

}  // namespace twistslam::registration
