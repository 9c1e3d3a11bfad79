#pragma once
// Private (Ceres): the parameter block of a pose in every Ceres problem of this module.
//
// A pose T (T_c_w of a keyframe, later T_w_o of an object) is a 7-vector
//   [tx, ty, tz, qx, qy, qz, qw]   (translation, then an Eigen-ordered unit quaternion)
// on the manifold R^3 x SO(3) = ProductManifold<EuclideanManifold<3>, EigenQuaternionManifold>.
// Its tangent is 6-dimensional, ordered [v; w] like our twists: t <- t + v and
// q <- [cos|w|, sin|w| w/|w|] * q (Ceres' quaternion retraction: left-multiplied, |w| is half
// the rotation angle). Cost functions give Jacobians with respect to the 7 ambient
// coordinates (analytic or autodiff alike); Ceres chains them with the manifold's
// PlusJacobian, so any residual family can be written either way against the same blocks.
#include <ceres/manifold.h>
#include <ceres/product_manifold.h>

#include <Eigen/Geometry>

#include "geometry/types.hpp"

namespace twistslam::optim::detail {

constexpr int kPoseSize = 7;
constexpr int kPoseTangentSize = 6;

using PoseManifold = ceres::ProductManifold<ceres::EuclideanManifold<3>,
                                            ceres::EigenQuaternionManifold>;

inline void pose_to_params(const Mat4& T, double* p) {
  Eigen::Map<Vec3> t(p);
  t = T.topRightCorner<3, 1>();
  Eigen::Quaterniond q(Mat3(T.topLeftCorner<3, 3>()));
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;  // canonical sign, cosmetic
  Eigen::Map<Eigen::Quaterniond>(p + 3) = q;
}

inline Mat4 params_to_pose(const double* p) {
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() =
      Eigen::Map<const Eigen::Quaterniond>(p + 3).normalized().toRotationMatrix();
  T.topRightCorner<3, 1>() = Eigen::Map<const Vec3>(p);
  return T;
}

// X' = T X for a pose block, usable with ceres::Jet (autodiff residual families).
template <typename T>
Eigen::Matrix<T, 3, 1> transform_point(const T* pose, const Eigen::Matrix<T, 3, 1>& X) {
  const Eigen::Map<const Eigen::Quaternion<T>> q(pose + 3);
  const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(pose);
  return q * X + t;
}

}  // namespace twistslam::optim::detail
