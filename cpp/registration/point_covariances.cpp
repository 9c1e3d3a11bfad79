#include "registration/point_covariances.hpp"

#include <stdexcept>

namespace twistslam::registration {

std::vector<Vec3> plane_normals(const std::vector<Vec3>& points, const KdTree& tree,
                                int num_neighbors, Neighborhoods* neighborhoods) {
  if (num_neighbors < 3 || tree.size() < num_neighbors)
    throw std::invalid_argument("plane_covariances: need num_neighbors >= 3 and at least "
                                "num_neighbors points");
  std::vector<Vec3> normals(points.size());
  Neighborhoods local;
  Neighborhoods* nb = neighborhoods != nullptr ? neighborhoods : &local;
  all_knn(points, tree, num_neighbors, nb);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int* neighbors = nb->indices.data() + i * num_neighbors;
    Vec3 mean = Vec3::Zero();
    for (int j = 0; j < num_neighbors; ++j) mean += points[neighbors[j]];
    mean /= static_cast<double>(num_neighbors);
    Mat3 scatter = Mat3::Zero();
    for (int j = 0; j < num_neighbors; ++j) {
      const Vec3 d = points[neighbors[j]] - mean;
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
