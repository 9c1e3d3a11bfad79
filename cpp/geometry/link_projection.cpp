#include "geometry/link_projection.hpp"

#include <cmath>
#include <stdexcept>

namespace twistslam::geometry {

Mat6 projector_free() { return Mat6::Identity(); }

Mat6 projector_planar(const Vec3& normal) {
  const double norm = normal.norm();
  if (!std::isfinite(norm) || norm < 1e-12) {
    throw std::invalid_argument("projector_planar: the plane normal must be finite and non-zero");
  }
  const Vec3 n = normal / norm;
  const Mat3 nnT = n * n.transpose();
  Mat6 Pi = Mat6::Zero();
  Pi.topLeftCorner<3, 3>() = Mat3::Identity() - nnT;
  Pi.bottomRightCorner<3, 3>() = nnT;
  return Pi;
}

int projector_dof(const Mat6& Pi) { return static_cast<int>(std::lround(Pi.trace())); }

}  // namespace twistslam::geometry
