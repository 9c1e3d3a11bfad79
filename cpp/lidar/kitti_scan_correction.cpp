#include "lidar/kitti_scan_correction.hpp"

#include <cmath>
#include <stdexcept>

namespace twistslam::lidar {

Points3 correct_kitti_scan(const Eigen::Ref<const Points3>& points_velo, double angle_deg) {
  if (!std::isfinite(angle_deg))
    throw std::invalid_argument("correct_kitti_scan: angle_deg must be finite");
  const double angle = angle_deg * M_PI / 180.0;
  const double c = std::cos(angle), s = std::sin(angle);
  Points3 out = points_velo;
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    const Vec3 p = out.row(i).transpose();
    const Vec3 axis = p.cross(Vec3::UnitZ());
    const double norm = axis.norm();
    if (!(norm > 0) || !std::isfinite(norm)) continue;
    const Vec3 k = axis / norm;
    // Rodrigues with k perpendicular to p (k.p = 0): R p = p cos + (k x p) sin.
    out.row(i) = (p * c + k.cross(p) * s).transpose();
  }
  return out;
}

}  // namespace twistslam::lidar
