#pragma once
// Private (Ceres): e_dyna of paper eq. 9 (TwistSLAM++), the reprojection of a point that
// belongs to a moving object.
//
//   X_c = T_c_w T_w_o X_o,   r = sqrt(inv_sigma2) * (z(X_c) - z_obs)
//
// z = [u, v, u_right] (stereo) or [u, v] (mono), the same measurement model, min_depth test
// and disparity_offset as e_stat (stereo_projection.hpp, reprojection_costs.hpp). Parameter
// blocks, in this order:
//   camera  T_c_w  7-vector [t, q] (pose_parameterization.hpp), as the BA's keyframe blocks
//   object  T_w_o  7-vector [t, q], as the object window's blocks (object_window.cpp)
//   point   X_o    3-vector in the object frame (constant over time: the object is rigid)
// Both poses must be expressed in the same world frame w. (The object window solves in a
// world translated to its centroid; a problem that mixes camera and object blocks must add
// both in one common frame.)
//
// Analytic Jacobians, in the convention of object_costs.hpp: the quaternions are normalised
// (the residual is invariant to their scale), the Jacobian is derived in the manifold tangent
// [v; w] of each pose block (t <- t + v, R <- Exp(2 w) R) and mapped to the 7 ambient
// coordinates by J_tangent P^T. With X_w = R_wo X_o + t_wo, Jz = dz/dX_c:
//   d/d(v_c, w_c) = Jz [I, -2 hat(R_cw X_w)]
//   d/d(v_o, w_o) = Jz R_cw [I, -2 hat(R_wo X_o)]
//   d/d X_o       = Jz R_cw R_wo
// Evaluation fails (Ceres rejects the step; the gate removes the residual) when X_c gets
// closer than min_depth to the left (or, stereo, the right) image plane, as for e_stat.
#include <ceres/sized_cost_function.h>

#include <cmath>

#include "geometry/so3.hpp"
#include "geometry/stereo_camera.hpp"
#include "optim/pose_parameterization.hpp"
#include "optim/se3_jet.hpp"
#include "optim/stereo_projection.hpp"

namespace twistslam::optim::detail {

// P_q^T = [q_w I + hat(q_v), -q_v] for a unit q: d/dw (tangent) -> d/dq (ambient) by
// J_ambient = J_w P_q^T (object_costs.hpp, tangent_to_ambient).
inline Eigen::Matrix<double, 3, 4> quaternion_tangent_to_ambient(const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 3, 4> Pt;
  Pt.leftCols<3>() = q.w() * Mat3::Identity() + geometry::hat(q.vec());
  Pt.col(3) = -q.vec();
  return Pt;
}

template <int kRows>
class DynamicReprojectionCost final
    : public ceres::SizedCostFunction<kRows, kPoseSize, kPoseSize, 3> {
 public:
  using Measurement = Eigen::Matrix<double, kRows, 1>;

  DynamicReprojectionCost(const geometry::StereoCamera* cam, const Measurement& z_obs,
                          double inv_sigma2, double min_depth)
      : cam_(cam), z_obs_(z_obs), sqrt_info_(std::sqrt(inv_sigma2)), min_depth_(min_depth) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* camera = parameters[0];  // T_c_w
    const double* object = parameters[1];  // T_w_o
    const Eigen::Quaterniond q_cw = pose_quaternion(camera);
    const Eigen::Quaterniond q_wo = pose_quaternion(object);
    const Mat3 R_cw = q_cw.toRotationMatrix();
    const Mat3 R_wo = q_wo.toRotationMatrix();
    const Eigen::Map<const Vec3> X_o(parameters[2]);
    const Vec3 rotated_X_o = R_wo * X_o;
    const Vec3 X_w = rotated_X_o + Eigen::Map<const Vec3>(object);
    const Vec3 rotated_X_w = R_cw * X_w;
    const Vec3 X_c = rotated_X_w + Eigen::Map<const Vec3>(camera);

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

    using AmbientJacobian = Eigen::Matrix<double, kRows, kPoseSize, Eigen::RowMajor>;
    if (jacobians[0]) {
      Eigen::Map<AmbientJacobian> J(jacobians[0]);
      J.template leftCols<3>() = Jz;
      J.template rightCols<4>() =
          (-2.0 * Jz * geometry::hat(rotated_X_w)) * quaternion_tangent_to_ambient(q_cw);
    }
    const Eigen::Matrix<double, kRows, 3> Jz_R_cw = Jz * R_cw;
    if (jacobians[1]) {
      Eigen::Map<AmbientJacobian> J(jacobians[1]);
      J.template leftCols<3>() = Jz_R_cw;
      J.template rightCols<4>() =
          (-2.0 * Jz_R_cw * geometry::hat(rotated_X_o)) * quaternion_tangent_to_ambient(q_wo);
    }
    if (jacobians[2]) {
      Eigen::Map<Eigen::Matrix<double, kRows, 3, Eigen::RowMajor>> J(jacobians[2]);
      J = Jz_R_cw * R_wo;
    }
    return true;
  }

 private:
  const geometry::StereoCamera* cam_;  // outlives the problem (owned by the caller)
  Measurement z_obs_;
  double sqrt_info_;
  double min_depth_;
};

using StereoDynamicReprojectionCost = DynamicReprojectionCost<3>;
using MonoDynamicReprojectionCost = DynamicReprojectionCost<2>;

// Stereo when u_right >= 0, mono otherwise (the convention of add_stereo_reprojection).
inline ceres::CostFunction* make_dynamic_reprojection_cost(const geometry::StereoCamera* cam,
                                                           const Vec2& uv, double u_right,
                                                           double inv_sigma2, double min_depth) {
  if (u_right >= 0) {
    return new StereoDynamicReprojectionCost(cam, Vec3(uv.x(), uv.y(), u_right), inv_sigma2,
                                             min_depth);
  }
  return new MonoDynamicReprojectionCost(cam, uv, inv_sigma2, min_depth);
}

}  // namespace twistslam::optim::detail
