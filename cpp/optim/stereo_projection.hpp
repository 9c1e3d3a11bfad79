#pragma once
// Private (Eigen only): the stereo / mono measurement model shared by the pose optimiser and
// the Ceres reprojection costs. A measurement is z = [u, v, u_right] (stereo) or [u, v]
// (mono); the point X_c is in the reference camera frame c, the left and right images see
// X_c + t_left and X_c + t_right (geometry/stereo_camera.hpp).
#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::optim::detail {

// Predicted measurement of X_c (kRows = 3 stereo, 2 mono) and, if J != nullptr, its Jacobian
// with respect to X_c. Returns false (outputs untouched) when the point is closer than
// min_depth to the left (or, for stereo, the right) image plane.
template <int kRows>
inline bool predict_measurement(const geometry::StereoCamera& cam, const Vec3& X_c,
                                double min_depth, Eigen::Matrix<double, kRows, 1>* z,
                                Eigen::Matrix<double, kRows, 3>* J) {
  static_assert(kRows == 2 || kRows == 3, "mono (2) or stereo (3) measurement");
  const Vec3 Xl = X_c + cam.t_left;
  if (!(Xl.z() > min_depth)) return false;
  const double il = 1.0 / Xl.z();
  double ir = 0;
  Vec3 Xr;
  if constexpr (kRows == 3) {
    Xr = X_c + cam.t_right;
    if (!(Xr.z() > min_depth)) return false;
    ir = 1.0 / Xr.z();
  }
  (*z)(0) = cam.fx * Xl.x() * il + cam.cx;
  (*z)(1) = cam.fy * Xl.y() * il + cam.cy;
  // the right image's principal point carries the pair's disparity offset (stereo_camera.hpp)
  if constexpr (kRows == 3) (*z)(2) = cam.fx * Xr.x() * ir + cam.cx + cam.disparity_offset;
  if (J) {
    J->row(0) << cam.fx * il, 0.0, -cam.fx * Xl.x() * il * il;
    J->row(1) << 0.0, cam.fy * il, -cam.fy * Xl.y() * il * il;
    if constexpr (kRows == 3) J->row(2) << cam.fx * ir, 0.0, -cam.fx * Xr.x() * ir * ir;
  }
  return true;
}

// Huber robust function of a squared whitened error s (Ceres' convention: rho(s) = s inside,
// 2 delta sqrt(s) - delta^2 outside) and its first derivative (the IRLS weight).
inline double huber_rho(double s, double delta) {
  return s <= delta * delta ? s : 2.0 * delta * std::sqrt(s) - delta * delta;
}
inline double huber_weight(double s, double delta) {
  return s <= delta * delta ? 1.0 : delta / std::sqrt(s);
}

}  // namespace twistslam::optim::detail
