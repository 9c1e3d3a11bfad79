#include "registration/point_covariances.hpp"

#include <cmath>
#include <stdexcept>

namespace twistslam::registration {

namespace {

// Newton steps on the normalised characteristic cubic; it converges from the left, quadratically
// unless the two smallest eigenvalues (nearly) coincide, where the normal is ill-defined anyway,
// and stops when x no longer moves. On the bench's car scans: 4-6 steps for 80-90 % of the
// points, at most 17; 30 is a safeguard that was never reached.
constexpr int kMaxNewtonSteps = 30;

// The unit eigenvector of the smallest eigenvalue of a symmetric 3x3 matrix, without the
// trigonometric closed form: B = (A - tr(A)/3 I) / s, s = sqrt(tr(B0^2) / 6), has eigenvalues
// 2 cos(.) in [-2, 2] and characteristic x^3 - 3x - det(B) = 0; its smallest root (in [-2, -1])
// is reached by Newton from -2, then the eigenvector is the largest cross product of two rows of
// B - x I (they span the plane orthogonal to it).
Vec3 smallest_eigenvector(const Mat3& A) {
  const double shift = A.trace() / 3.0;
  Mat3 B = A;
  B.diagonal().array() -= shift;
  const double p2 = (B * B).trace() / 6.0;
  if (!(p2 > 0.0)) return Vec3::UnitX();  // isotropic: any direction
  B /= std::sqrt(p2);
  const double det = B.determinant();
  double x = -2.0;
  for (int step = 0; step < kMaxNewtonSteps; ++step) {
    const double f = x * x * x - 3.0 * x - det, df = 3.0 * x * x - 3.0;
    if (!(df > 0.0) || f >= 0.0) break;
    const double next = x - f / df;
    if (next <= x) break;
    x = next;
  }
  B.diagonal().array() -= x;
  const Vec3 c01 = B.row(0).cross(B.row(1)), c02 = B.row(0).cross(B.row(2)),
             c12 = B.row(1).cross(B.row(2));
  const double n01 = c01.squaredNorm(), n02 = c02.squaredNorm(), n12 = c12.squaredNorm();
  if (n01 >= n02 && n01 >= n12 && n01 > 0.0) return c01 / std::sqrt(n01);
  if (n02 >= n12 && n02 > 0.0) return c02 / std::sqrt(n02);
  if (n12 > 0.0) return c12 / std::sqrt(n12);
  return Vec3::UnitX();
}

}  // namespace

std::vector<Vec3> plane_normals(const std::vector<Vec3>& points, const KdTree& tree,
                                int num_neighbors, Neighborhoods* neighborhoods,
                                PointGrid* grid) {
  if (num_neighbors < 3 || tree.size() < num_neighbors)
    throw std::invalid_argument("plane_covariances: need num_neighbors >= 3 and at least "
                                "num_neighbors points");
  std::vector<Vec3> normals(points.size());
  Neighborhoods local;
  Neighborhoods* nb = neighborhoods != nullptr ? neighborhoods : &local;
  all_knn(points, tree, num_neighbors, nb, nullptr, grid);
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
    Mat3 scatter;
    scatter(0, 0) = sxx - sx * sx * inv_k;
    scatter(1, 1) = syy - sy * sy * inv_k;
    scatter(2, 2) = szz - sz * sz * inv_k;
    scatter(0, 1) = scatter(1, 0) = sxy - sx * sy * inv_k;
    scatter(0, 2) = scatter(2, 0) = sxz - sx * sz * inv_k;
    scatter(1, 2) = scatter(2, 1) = syz - sy * sz * inv_k;
    normals[i] = smallest_eigenvector(scatter);
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
