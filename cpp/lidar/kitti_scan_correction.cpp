#include "lidar/kitti_scan_correction.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace twistslam::lidar {

namespace {

// p rotated up by the angle whose cosine and sine are c, s (see correct_kitti_scan)
Vec3 raised(const Vec3& p, double c, double s) {
  const Vec3 axis = p.cross(Vec3::UnitZ());
  const double norm = axis.norm();
  if (!(norm > 0) || !std::isfinite(norm)) return p;
  const Vec3 k = axis / norm;
  // Rodrigues with k perpendicular to p (k.p = 0): R p = p cos + (k x p) sin.
  return p * c + k.cross(p) * s;
}

}  // namespace

Points3 correct_kitti_scan(const Eigen::Ref<const Points3>& points_velo, double angle_deg) {
  if (!std::isfinite(angle_deg))
    throw std::invalid_argument("correct_kitti_scan: angle_deg must be finite");
  const double angle = angle_deg * M_PI / 180.0;
  const double c = std::cos(angle), s = std::sin(angle);
  Points3 out = points_velo;
  for (Eigen::Index i = 0; i < out.rows(); ++i) out.row(i) = raised(out.row(i).transpose(), c, s).transpose();
  return out;
}

void scan_to_camera(const Eigen::Ref<const ScanRows>& points_velo, const Mat4& T_c_velo,
                    double angle_deg, Eigen::Ref<ScanRows> velo, Eigen::Ref<ScanRows> camera) {
  const Eigen::Index n = points_velo.rows(), cols = points_velo.cols();
  if (cols < 3)
    throw std::invalid_argument("scan_to_camera: a scan needs at least 3 columns (x, y, z), got " +
                                std::to_string(cols));
  if (velo.rows() != n || velo.cols() != cols || camera.rows() != n || camera.cols() != cols)
    throw std::invalid_argument("scan_to_camera: the outputs must have the scan's shape");
  if (!std::isfinite(angle_deg)) throw std::invalid_argument("scan_to_camera: angle_deg must be finite");
  if (!T_c_velo.allFinite()) throw std::invalid_argument("scan_to_camera: T_c_velo contains NaN or Inf");
  const double angle = angle_deg * M_PI / 180.0;
  const double c = std::cos(angle), s = std::sin(angle);
  const Mat3 R = T_c_velo.topLeftCorner<3, 3>();
  const Vec3 t = T_c_velo.topRightCorner<3, 1>();
  for (Eigen::Index i = 0; i < n; ++i) {
    const float* in = points_velo.data() + i * points_velo.outerStride();
    float* v = velo.data() + i * velo.outerStride();
    float* x = camera.data() + i * camera.outerStride();
    Vec3 p(in[0], in[1], in[2]);
    if (angle != 0) {
      // the corrected point as stored (float), so that the camera frame's point is exactly
      // the transform of the velo output
      p = raised(p, c, s).cast<float>().cast<double>();
    }
    const Vec3 q = R * p + t;
    for (int k = 0; k < 3; ++k) {
      v[k] = static_cast<float>(p[k]);
      x[k] = static_cast<float>(q[k]);
    }
    for (Eigen::Index k = 3; k < cols; ++k) v[k] = x[k] = in[k];
  }
}

}  // namespace twistslam::lidar
