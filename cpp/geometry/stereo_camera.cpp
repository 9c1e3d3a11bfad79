#include "geometry/stereo_camera.hpp"

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace twistslam::geometry {

StereoCamera StereoCamera::from_kitti(const Mat34& P_left, const Mat34& P_right, int width,
                                      int height, double disparity_offset) {
  const Mat3 K_left = P_left.leftCols<3>();
  const Mat3 K_right = P_right.leftCols<3>();
  if (!P_left.allFinite() || !P_right.allFinite() || K_left(0, 0) <= 0 || K_left(1, 1) <= 0) {
    throw std::invalid_argument("StereoCamera.from_kitti: projection matrices must be finite "
                                "with positive focal lengths");
  }
  // Rectified images share one intrinsic matrix; 1e-6 relative absorbs text round-off.
  if ((K_left - K_right).cwiseAbs().maxCoeff() > 1e-6 * K_left(0, 0)) {
    throw std::invalid_argument("StereoCamera.from_kitti: P_left and P_right have different "
                                "intrinsics; the pair is not rectified");
  }
  // A few pixels at most: a larger one is a wrong calibration, not a rectification residual.
  if (!std::isfinite(disparity_offset) || std::abs(disparity_offset) > 8.0) {
    throw std::invalid_argument("StereoCamera.from_kitti: disparity_offset must be finite and "
                                "within +-8 px, got " + std::to_string(disparity_offset));
  }
  if (width < 0 || height < 0) {
    throw std::invalid_argument("StereoCamera.from_kitti: negative image size");
  }
  StereoCamera cam;
  cam.fx = K_left(0, 0);
  cam.fy = K_left(1, 1);
  cam.cx = K_left(0, 2);
  cam.cy = K_left(1, 2);
  cam.t_left = K_left.inverse() * P_left.col(3);
  cam.t_right = K_left.inverse() * P_right.col(3);
  cam.baseline = cam.t_left.x() - cam.t_right.x();
  if (!(cam.baseline > 0)) {
    throw std::invalid_argument("StereoCamera.from_kitti: the right camera must lie to the right "
                                "of the left one (baseline " + std::to_string(cam.baseline) + ")");
  }
  cam.width = width;
  cam.height = height;
  cam.disparity_offset = disparity_offset;
  return cam;
}

Mat3 StereoCamera::K() const {
  Mat3 K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

namespace {
Vec2 pinhole(const StereoCamera& c, const Vec3& X) {
  return Vec2(c.fx * X.x() / X.z() + c.cx, c.fy * X.y() / X.z() + c.cy);
}
}  // namespace

Vec2 StereoCamera::project(const Vec3& X_c) const { return pinhole(*this, X_c + t_left); }

Vec2 StereoCamera::project_right(const Vec3& X_c) const {
  return pinhole(*this, X_c + t_right) + Vec2(disparity_offset, 0.0);
}

double StereoCamera::depth_from_disparity(double disparity) const {
  const double d = disparity + disparity_offset;
  return d > 0 ? fx * baseline / d : -1.0;
}

Vec3 StereoCamera::backproject(const Vec2& uv, double depth) const {
  const Vec3 X_left((uv.x() - cx) * depth / fx, (uv.y() - cy) * depth / fy, depth);
  return X_left - t_left;
}

Vec3 StereoCamera::triangulate(const Vec2& uv_left, double disparity) const {
  const double depth = depth_from_disparity(disparity);
  if (!(depth > 0)) return Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  return backproject(uv_left, depth);
}

bool StereoCamera::in_image(const Vec2& uv, double border) const {
  return uv.x() >= border && uv.y() >= border && uv.x() <= width - 1 - border &&
         uv.y() <= height - 1 - border;
}

}  // namespace twistslam::geometry
