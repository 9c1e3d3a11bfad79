#pragma once
// Private (Ceres): cost functions of the reprojection residual families.
//
// ReprojectionCost<3> (stereo) / ReprojectionCost<2> (mono): e_stat of paper eq. 9, the
// whitened error r = sqrt(inv_sigma2) * (z(T_c_w X_w) - z_obs), z = [u, v, u_right] or [u, v]
// (stereo_projection.hpp), parameter blocks: pose T_c_w (7, pose_parameterization.hpp) and
// point X_w (3). Analytic Jacobians (about 3x faster than autodiff for this residual).
// Evaluation fails (Ceres rejects the step) when the point gets closer than min_depth to a
// camera, which enforces cheirality.
#include <ceres/sized_cost_function.h>

#include "geometry/so3.hpp"
#include "geometry/stereo_camera.hpp"
#include "optim/pose_parameterization.hpp"
#include "optim/stereo_projection.hpp"

namespace twistslam::optim::detail {

// d(R(q) X) / d(qx, qy, qz, qw) for a unit quaternion q = (v, w):
// R X = X + 2 w (v x X) + 2 v x (v x X).
inline Eigen::Matrix<double, 3, 4> rotate_jacobian_quaternion(const Eigen::Quaterniond& q,
                                                               const Vec3& X) {
  const Vec3 v = q.vec();
  const double w = q.w();
  const Mat3 Xx = geometry::hat(X);
  Eigen::Matrix<double, 3, 4> J;
  J.leftCols<3>() = -2.0 * w * Xx +
                    2.0 * (v.dot(X) * Mat3::Identity() + v * X.transpose() - 2.0 * X * v.transpose());
  J.col(3) = 2.0 * v.cross(X);
  return J;
}

template <int kRows>
class ReprojectionCost final : public ceres::SizedCostFunction<kRows, kPoseSize, 3> {
 public:
  using Measurement = Eigen::Matrix<double, kRows, 1>;

  ReprojectionCost(const geometry::StereoCamera* cam, const Measurement& z_obs,
                   double inv_sigma2, double min_depth)
      : cam_(cam), z_obs_(z_obs), sqrt_info_(std::sqrt(inv_sigma2)), min_depth_(min_depth) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* pose = parameters[0];
    const Eigen::Map<const Eigen::Quaterniond> q(pose + 3);
    const Mat3 R = q.toRotationMatrix();
    const Eigen::Map<const Vec3> X_w(parameters[1]);
    const Vec3 X_c = R * X_w + Eigen::Map<const Vec3>(pose);
    Measurement z;
    Eigen::Matrix<double, kRows, 3> Jz;
    const bool want_jacobian = jacobians != nullptr;
    if (!predict_measurement<kRows>(*cam_, X_c, min_depth_, &z, want_jacobian ? &Jz : nullptr)) {
      return false;
    }
    Eigen::Map<Measurement> r(residuals);
    r = sqrt_info_ * (z - z_obs_);
    if (!want_jacobian) return true;
    Jz *= sqrt_info_;
    if (jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, kRows, kPoseSize, Eigen::RowMajor>> J(jacobians[0]);
      J.template leftCols<3>() = Jz;
      J.template rightCols<4>() = Jz * rotate_jacobian_quaternion(q, X_w);
    }
    if (jacobians[1]) {
      Eigen::Map<Eigen::Matrix<double, kRows, 3, Eigen::RowMajor>> J(jacobians[1]);
      J = Jz * R;
    }
    return true;
  }

 private:
  const geometry::StereoCamera* cam_;  // outlives the problem (owned by the caller)
  Measurement z_obs_;
  double sqrt_info_;
  double min_depth_;
};

using StereoReprojectionCost = ReprojectionCost<3>;
using MonoReprojectionCost = ReprojectionCost<2>;

}  // namespace twistslam::optim::detail
