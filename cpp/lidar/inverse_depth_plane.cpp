#include "lidar/inverse_depth_plane.hpp"

#include <cmath>

#include "geometry/types.hpp"

namespace twistslam::lidar {

InverseDepthPlane fit_inverse_depth_plane(const std::vector<PixelDepth>& returns) {
  InverseDepthPlane out;
  if (returns.size() < 3) return out;
  // Normal equations of the weighted rows w_i [du dv 1] theta = w_i / z_i with w_i = z_i.
  Mat3 A = Mat3::Zero();
  Vec3 b = Vec3::Zero();
  for (const PixelDepth& r : returns) {
    const Vec3 row(r.depth * r.du, r.depth * r.dv, r.depth);
    A.noalias() += row * row.transpose();
    b += row;  // w_i * (w_i / z_i) = w_i
  }
  const Eigen::LDLT<Mat3> ldlt(A);
  // rcond below 1e-9: the returns are (numerically) collinear in the image, the plane's tilt
  // across them is unconstrained.
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.rcond() < 1e-9) return out;
  const Vec3 theta = ldlt.solve(b);
  if (!(theta.z() > 0) || !theta.allFinite()) return out;
  double sum_sq = 0;
  for (const PixelDepth& r : returns) {
    const double inv_fit = theta.x() * r.du + theta.y() * r.dv + theta.z();
    const double rel = r.depth * inv_fit - 1.0;  // (z_i - z_fit) / z_fit at this return
    sum_sq += rel * rel;
  }
  out.ok = true;
  out.depth = 1.0 / theta.z();
  out.rms_relative = std::sqrt(sum_sq / static_cast<double>(returns.size()));
  return out;
}

}  // namespace twistslam::lidar
