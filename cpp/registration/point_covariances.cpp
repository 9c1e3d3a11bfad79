#include "registration/point_covariances.hpp"

#include <stdexcept>

namespace twistslam::registration {

std::vector<Vec3> plane_normals(const std::vector<Vec3>& points, const KdTree& tree,
                                int num_neighbors, Neighborhoods* neighborhoods) {
  if (num_neighbors < 3 || tree.size() < num_neighbors)
    throw std::invalid_argument("plane_covariances: need num_neighbors >= 3 and at least "
                                "num_neighbors points");
  std::vector<Vec3> normals(points.size());
  std::vector<Neighbor> neighbors;
  if (neighborhoods != nullptr) {
    neighborhoods->size = num_neighbors;
    neighborhoods->indices.resize(points.size() * num_neighbors);
    neighborhoods->radius2_m2.resize(points.size());
  }
  for (const int i : tree.leaf_order()) {
    tree.knn(points[i], num_neighbors, &neighbors);
    if (neighborhoods != nullptr) {
      int* out = neighborhoods->indices.data() + static_cast<std::size_t>(i) * num_neighbors;
      for (int j = 0; j < num_neighbors; ++j) out[j] = neighbors[j].index;
      neighborhoods->radius2_m2[i] = neighbors.back().squared_distance_m2;
    }
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
    eig.computeDirect(scatter, Eigen::ComputeEigenvectors);
    normals[i] = eig.eigenvectors().col(0);  // ascending eigenvalues: the normal first
  }
  return normals;
}

std::vector<Mat3> plane_covariances(const std::vector<Vec3>& points, const KdTree& tree,
                                    int num_neighbors, double plane_epsilon) {
  const std::vector<Vec3> normals = plane_normals(points, tree, num_neighbors);
  std::vector<Mat3> covariances(normals.size());
  for (std::size_t i = 0; i < normals.size(); ++i)
    covariances[i] = plane_covariance(normals[i], plane_epsilon);
  return covariances;
}

}  // namespace twistslam::registration
