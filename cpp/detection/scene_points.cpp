#include "detection/scene_points.hpp"

#include <algorithm>
#include <cmath>

namespace twistslam::detection {

double selection_half_angle_deg(const DetectorOptions& o) {
  return std::min(180.0, o.fov_half_angle_deg + o.fov_margin_deg);
}

SceneSelection select_scene_points(const Eigen::Ref<const Points3>& points_c,
                                   const DetectorOptions& o) {
  SceneSelection out;
  out.points.reserve(static_cast<std::size_t>(points_c.rows()));
  // the field of view widened by the margin: a car straddling the border is clustered whole
  const double fov_deg = selection_half_angle_deg(o);
  // |x| <= z tan(fov) with z > 0, without an atan per point
  const double tan_fov = fov_deg >= 90.0 ? 0.0 : std::tan(fov_deg * M_PI / 180.0);
  const double min_sq = o.min_range_m * o.min_range_m, max_sq = o.max_range_m * o.max_range_m;
  for (Eigen::Index i = 0; i < points_c.rows(); ++i) {
    const double x = points_c(i, 0), y = points_c(i, 1), z = points_c(i, 2);
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      ++out.num_non_finite;
      continue;
    }
    const double r_sq = x * x + z * z;
    if (r_sq < min_sq || r_sq > max_sq) continue;
    if (o.front_only) {
      if (fov_deg < 90.0) {
        if (z <= 0.0 || std::abs(x) > z * tan_fov) continue;
      } else if (fov_deg < 180.0) {  // wider than a half plane: test the angle
        if (std::abs(std::atan2(x, z)) > fov_deg * M_PI / 180.0) continue;
      }
    }
    out.points.push_back({static_cast<float>(x), static_cast<float>(z), static_cast<float>(-y),
                          static_cast<int>(i)});
  }
  return out;
}

}  // namespace twistslam::detection
