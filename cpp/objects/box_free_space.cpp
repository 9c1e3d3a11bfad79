#include "objects/box_free_space.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace twistslam::objects {

BoxRayCounts count_box_rays(const Points3& scan_c, const Mat4& T_c_o, const Vec3& size_lwh,
                            const Vec3& sensor_c, double shrink_m) {
  BoxRayCounts counts;
  const Mat3 R = T_c_o.topLeftCorner<3, 3>();
  const Vec3 centre = T_c_o.topRightCorner<3, 1>();
  // box axes: x length, y height, z width
  const Vec3 half(size_lwh.x() / 2, size_lwh.z() / 2, size_lwh.y() / 2);
  const Vec3 inner = (half - Vec3::Constant(shrink_m)).cwiseMax(0.0);
  const double radius = half.norm();
  const Vec3 to_centre = centre - sensor_c;
  const double centre_range = to_centre.norm();
  if (!(centre_range > radius)) return counts;  // the sensor inside the box: no verdict
  const Vec3 o = R.transpose() * (sensor_c - centre);  // the ray origin in the box frame
  for (Eigen::Index i = 0; i < scan_c.rows(); ++i) {
    const Vec3 p = scan_c.row(i).transpose();
    const Vec3 d = p - sensor_c;
    const double range = d.norm();
    if (!std::isfinite(range) || range < centre_range - radius) continue;  // ends before the box
    // the ray's closest approach to the centre must lie within the box's bounding sphere
    const double along = d.dot(to_centre) / range;
    if (along <= 0 || centre_range * centre_range - along * along > radius * radius) continue;
    const Vec3 q = R.transpose() * (p - centre);
    if ((q.cwiseAbs() - half).maxCoeff() <= 0) {
      ++counts.inside;
      continue;
    }
    if ((inner.array() <= 0).any()) continue;
    // slab test of the segment o -> q against the inner box: it crosses and leaves before q
    const Vec3 dir = q - o;
    double t_in = 0, t_out = 1;
    bool hit = true;
    for (int k = 0; k < 3 && hit; ++k) {
      if (std::abs(dir[k]) < 1e-12) {
        hit = std::abs(o[k]) <= inner[k];
        continue;
      }
      double t0 = (-inner[k] - o[k]) / dir[k], t1 = (inner[k] - o[k]) / dir[k];
      if (t0 > t1) std::swap(t0, t1);
      t_in = std::max(t_in, t0);
      t_out = std::min(t_out, t1);
      hit = t_in <= t_out;
    }
    if (hit && t_out < 1) ++counts.through;
  }
  return counts;
}

Points3 returns_near_box_rays(const Points3& scan_c, const Mat4& T_c_o, const Vec3& size_lwh,
                              const Vec3& sensor_c, double reach_m) {
  // any such box lies in the sphere of the box's bounding radius plus the reach
  const double radius = 0.5 * size_lwh.norm() + std::max(0.0, reach_m);
  const Vec3 to_centre = T_c_o.topRightCorner<3, 1>() - sensor_c;
  const double centre_range = to_centre.norm();
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < scan_c.rows(); ++i) {
    const Vec3 d = scan_c.row(i).transpose() - sensor_c;
    const double range = d.norm();
    if (!std::isfinite(range) || range < centre_range - radius || !(range > 0)) continue;
    const double along = d.dot(to_centre) / range;
    if (along <= 0 || centre_range * centre_range - along * along > radius * radius) continue;
    kept.push_back(i);
  }
  Points3 out(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t k = 0; k < kept.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = scan_c.row(kept[k]);
  return out;
}

}  // namespace twistslam::objects
