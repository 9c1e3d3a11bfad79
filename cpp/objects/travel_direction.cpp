#include "objects/travel_direction.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>

namespace twistslam::objects {

void TravelDirection::add_step(const Vec3& d_o, const Vec3& up_o) {
  if (!d_o.allFinite() || !up_o.allFinite() || !(up_o.norm() > 0)) return;
  const Vec3 n = up_o.normalized();
  const Vec3 d = d_o - n * n.dot(d_o);  // in the road plane
  moments += d * d.transpose();
  path_m += d.norm();
  net_o += d;
}

Vec3 TravelDirection::axis(double min_path_m, double min_anisotropy, double min_straightness) const {
  if (!(path_m >= min_path_m) || !moments.allFinite()) return Vec3::Zero();
  if (net_o.norm() < min_straightness * path_m) return Vec3::Zero();
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(moments);  // ascending eigenvalues
  const Vec3 lambda = eig.eigenvalues();
  if (!(lambda(2) > 0) || lambda(2) < min_anisotropy * std::max(lambda(1), 0.0))
    return Vec3::Zero();
  return eig.eigenvectors().col(2).normalized();
}

}  // namespace twistslam::objects
