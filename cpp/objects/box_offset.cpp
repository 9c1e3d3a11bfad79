#include "objects/box_offset.hpp"

#include <cmath>

#include "geometry/so3.hpp"

namespace twistslam::objects {

namespace {

// the weighted mean of the samples with use[k], rotations about R_ref's tangent space
BoxOffset weighted_mean(const std::vector<BoxOffsetSample>& samples, const std::vector<char>& use,
                        const Mat3& R_ref) {
  BoxOffset out;
  double total = 0;
  Vec3 t = Vec3::Zero(), omega = Vec3::Zero();
  for (size_t k = 0; k < samples.size(); ++k) {
    if (!use[k]) continue;
    const Mat4& C = samples[k].T_o_box;
    const double w = samples[k].weight;
    total += w;
    t += w * C.topRightCorner<3, 1>();
    omega += w * geometry::so3_log(R_ref.transpose() * C.topLeftCorner<3, 3>());
    ++out.inliers;
  }
  if (!(total > 0)) return out;
  out.valid = true;
  out.T_o_box.topLeftCorner<3, 3>() = R_ref * geometry::so3_exp(omega / total);
  out.T_o_box.topRightCorner<3, 1>() = t / total;
  return out;
}

}  // namespace

BoxOffset mean_box_offset(const std::vector<BoxOffsetSample>& samples, const BoxOffsetOptions& options) {
  std::vector<char> use(samples.size(), 0);
  for (size_t k = 0; k < samples.size(); ++k) {
    const BoxOffsetSample& s = samples[k];
    use[k] = s.weight > 0 && std::isfinite(s.weight) && s.T_o_box.allFinite() &&
             geometry::so3_log(s.T_o_box.topLeftCorner<3, 3>()).norm() <= options.max_rotation_rad;
  }
  const BoxOffset first = weighted_mean(samples, use, Mat3::Identity());
  if (!first.valid) return first;
  const Mat3 R_first = first.T_o_box.topLeftCorner<3, 3>();
  for (size_t k = 0; k < samples.size(); ++k) {
    if (!use[k]) continue;
    const Mat4& C = samples[k].T_o_box;
    const double dt = (C.topRightCorner<3, 1>() - first.T_o_box.topRightCorner<3, 1>()).norm();
    const double dr = geometry::so3_log(R_first.transpose() * C.topLeftCorner<3, 3>()).norm();
    use[k] = dt <= options.inlier_translation_m && dr <= options.inlier_rotation_rad;
  }
  const BoxOffset second = weighted_mean(samples, use, R_first);
  return second.valid ? second : first;
}

}  // namespace twistslam::objects
