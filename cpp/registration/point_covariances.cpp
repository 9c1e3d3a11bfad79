#include "registration/point_covariances.hpp"

#include <cmath>
#include <stdexcept>

#include "registration/smallest_eigenvectors.hpp"

namespace twistslam::registration {

std::vector<Vec3> plane_normals(const std::vector<Vec3>& points, const KdTree& tree,
                                int num_neighbors, Neighborhoods* neighborhoods,
                                PointGrid* grid) {
  if (num_neighbors < 3 || tree.size() < num_neighbors)
    throw std::invalid_argument("plane_covariances: need num_neighbors >= 3 and at least "
                                "num_neighbors points");
  Neighborhoods local;
  Neighborhoods* nb = neighborhoods != nullptr ? neighborhoods : &local;
  all_knn(points, tree, num_neighbors, nb, nullptr, grid);
  SymmetricMatrices scatters;
  scatters.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int* neighbors = nb->indices.data() + i * num_neighbors;
    // One pass over the neighbours, relative to the point itself (their spread is a few cm, so
    // no precision is lost): scatter = sum d d^T - (sum d)(sum d)^T / k, upper triangle.
    const Vec3& centre = points[i];
    double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
    for (int j = 0; j < num_neighbors; ++j) {
      const Vec3& p = points[neighbors[j]];
      const double dx = p[0] - centre[0], dy = p[1] - centre[1], dz = p[2] - centre[2];
      sx += dx, sy += dy, sz += dz;
      sxx += dx * dx, sxy += dx * dy, sxz += dx * dz;
      syy += dy * dy, syz += dy * dz, szz += dz * dz;
    }
    const double inv_k = 1.0 / num_neighbors;
    scatters.a00[i] = sxx - sx * sx * inv_k;
    scatters.a11[i] = syy - sy * sy * inv_k;
    scatters.a22[i] = szz - sz * sz * inv_k;
    scatters.a01[i] = sxy - sx * sy * inv_k;
    scatters.a02[i] = sxz - sx * sz * inv_k;
    scatters.a12[i] = syz - sy * sz * inv_k;
  }
  return smallest_eigenvectors(scatters);  // eight at a time
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
