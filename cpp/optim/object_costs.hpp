#pragma once
// Private (Ceres): cost functions of the object residual families of paper eq. 9, on object
// pose blocks T_w_o (7-vectors [t, q], pose_parameterization.hpp). With
//   xi~(a, b) = log(T_b T_a^-1)   (se3_jet.hpp; the twist of eq. 2, T_b = exp(xi~) T_a)
// and a diagonal weight W = diag(1/sigma_t x3, 1/sigma_r x3) (the rows of a twist are
// [v; w]: metres / radians per frame):
//
//   ConstantVelocityCost  e_const  W Pi (xi~(T_i, T_i+1) - xi~(T_i-1, T_i))   3 blocks
//   DetectionTwistCost    e_det    W Pi (xi_d - xi~(T_i, T_i+1))  (eq. 5)       2 blocks
//   DetectionPoseCost     prior    W [t - t_det; log(R_det^T R)]                1 block
//   LinkCost              e_link   W (I - Pi) xi~(T_i, T_i+1)                   2 blocks
//
// Pi (geometry/link_projection.hpp) keeps the twist components the mechanical link allows:
// e_const and e_det only compare those (the paper projects every twist by Pi), and e_link is
// the stiff penalty on the rest, which stands in for the hard constraint
// T_i+1 = exp(Pi xi) T_i of eq. 2 when poses (not projected twists) are the unknowns.
// The weights W multiply the residual, so a Huber threshold is in sigmas; an information
// scale k (detection_weight) multiplies W^2, i.e. the residual by sqrt(k).
//
// Analytic Jacobians: autodiff of the same logs on Jets took ~95 us per Jacobian evaluation
// of a 10-frame window (36 blocks), these ~20 us (1.2 us e_const, 0.75 us e_det / e_link,
// 0.2 us prior; loaded 2-core machine). Derivation, for the manifold tangent
// [v; w] of a block (t <- t + v, R <- Exp(2 w) R, pose_parameterization.hpp): that step is
// the left SE(3) perturbation eps = B(t) [v; w], B(t) = [I, 2 hat(t); 0, 2 I], and
//   d xi~ / d eps_b = J_l^-1(xi~),   d xi~ / d eps_a = -J_l^-1(xi~) Ad(exp xi~) = -J_l^-1(-xi~)
// (Barfoot, sec. 7.1.5). Ceres wants the Jacobian in the 7 ambient coordinates and chains it
// with the manifold's PlusJacobian P; since the costs normalise q (scale invariant), the
// ambient gradient lies in span(P) and equals J_tangent P^T exactly (P_q has orthonormal
// columns for a unit q).
#include <ceres/sized_cost_function.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <stdexcept>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "optim/pose_parameterization.hpp"
#include "optim/se3_jet.hpp"

namespace twistslam::optim::detail {

using PoseJacobian = Eigen::Matrix<double, 6, kPoseSize, Eigen::RowMajor>;

// diag(1/sigma_t x3, 1/sigma_r x3) * sqrt(information_scale); throws for sigma <= 0.
inline Vec6 twist_weights(double sigma_t, double sigma_r, double information_scale = 1.0) {
  if (!(sigma_t > 0) || !(sigma_r > 0) || !std::isfinite(sigma_t) || !std::isfinite(sigma_r) ||
      !(information_scale >= 0) || !std::isfinite(information_scale)) {
    throw std::invalid_argument(
        "object cost: sigmas must be finite and > 0, the information scale finite and >= 0");
  }
  const double s = std::sqrt(information_scale);
  Vec6 w;
  w << Vec3::Constant(s / sigma_t), Vec3::Constant(s / sigma_r);
  return w;
}

// d / d(v, w) -> d / d(t, q): J_ambient = J_tangent P^T, P_q^T = [q_w I + hat(q_v), -q_v].
inline void tangent_to_ambient(const Mat6& J_tangent, const double* pose, double* out) {
  const Eigen::Quaterniond q = pose_quaternion(pose);
  Eigen::Matrix<double, 3, 4> Pt;
  Pt.leftCols<3>() = q.w() * Mat3::Identity() + geometry::hat(q.vec());
  Pt.col(3) = -q.vec();
  Eigen::Map<PoseJacobian> J(out);
  J.leftCols<3>() = J_tangent.leftCols<3>();
  J.rightCols<4>() = J_tangent.rightCols<3>() * Pt;
}

// xi~ = log(T_b T_a^-1) and, if Ja / Jb are given, its Jacobians in the tangents of a and b.
// Jb = J_l^-1(xi~) B(t_b); Ja = -J_l^-1(xi~) Ad(T_b T_a^-1) B(t_a) = -Jb blockdiag(R, R),
// R = R_b R_a^T (as Ad([R, t]) B(t_a) = B(t_b) blockdiag(R, R) for t = t_b - R t_a): one
// SE(3) Jacobian per pair instead of two.
inline Vec6 relative_twist_jacobians(const double* a, const double* b, Mat6* Ja, Mat6* Jb) {
  const Vec6 xi = relative_twist(a, b);
  if (!Ja && !Jb) return xi;
  const Mat6 Jl_inv = geometry::se3_left_jacobian_inverse(xi);
  const Mat3 tb_hat = geometry::hat(Eigen::Map<const Vec3>(b));
  Mat6 J;  // J_l^-1 [I, 2 hat(t_b); 0, 2 I]
  J.leftCols<3>() = Jl_inv.leftCols<3>();
  J.topRightCorner<3, 3>() =
      2.0 * (Jl_inv.topLeftCorner<3, 3>() * tb_hat + Jl_inv.topRightCorner<3, 3>());
  J.bottomRightCorner<3, 3>() = 2.0 * Jl_inv.bottomRightCorner<3, 3>();
  if (Ja) {
    const Mat3 R = (pose_quaternion(b) * pose_quaternion(a).conjugate()).toRotationMatrix();
    Ja->leftCols<3>() = -J.leftCols<3>() * R;
    Ja->rightCols<3>() = -J.rightCols<3>() * R;
  }
  if (Jb) *Jb = J;
  return xi;
}

// e_const: M (xi~(b, c) - xi~(a, b)), M = W Pi.
class ConstantVelocityCost final : public ceres::SizedCostFunction<6, 7, 7, 7> {
 public:
  explicit ConstantVelocityCost(const Mat6& M) : M_(M) {}
  bool Evaluate(double const* const* p, double* residuals, double** jac) const override {
    const bool want = jac && (jac[0] || jac[1] || jac[2]);
    Mat6 Ja_ab, Jb_ab, Ja_bc, Jb_bc;
    const Vec6 xi_ab = relative_twist_jacobians(p[0], p[1], want ? &Ja_ab : nullptr,
                                                want ? &Jb_ab : nullptr);
    const Vec6 xi_bc = relative_twist_jacobians(p[1], p[2], want ? &Ja_bc : nullptr,
                                                want ? &Jb_bc : nullptr);
    Eigen::Map<Vec6> r(residuals);
    r = M_ * (xi_bc - xi_ab);
    if (!want) return true;
    if (jac[0]) tangent_to_ambient(-M_ * Ja_ab, p[0], jac[0]);
    if (jac[1]) tangent_to_ambient(M_ * (Ja_bc - Jb_ab), p[1], jac[1]);
    if (jac[2]) tangent_to_ambient(M_ * Jb_bc, p[2], jac[2]);
    return true;
  }

 private:
  Mat6 M_;
};

// e_det: M (xi_d - xi~(a, b)), M = W Pi; e_link: M xi~(a, b), M = W (I - Pi).
class RelativeTwistCost final : public ceres::SizedCostFunction<6, 7, 7> {
 public:
  // r = sign * M (xi~ - offset): e_det is (M, xi_d, -1), e_link (M, 0, +1).
  RelativeTwistCost(const Mat6& M, const Vec6& offset, double sign)
      : M_(sign * M), offset_(offset) {}
  bool Evaluate(double const* const* p, double* residuals, double** jac) const override {
    const bool want = jac && (jac[0] || jac[1]);
    Mat6 Ja, Jb;
    const Vec6 xi =
        relative_twist_jacobians(p[0], p[1], want ? &Ja : nullptr, want ? &Jb : nullptr);
    Eigen::Map<Vec6> r(residuals);
    r = M_ * (xi - offset_);
    if (!want) return true;
    if (jac[0]) tangent_to_ambient(M_ * Ja, p[0], jac[0]);
    if (jac[1]) tangent_to_ambient(M_ * Jb, p[1], jac[1]);
    return true;
  }

 private:
  Mat6 M_;
  Vec6 offset_;
};
using DetectionTwistCost = RelativeTwistCost;
using LinkCost = RelativeTwistCost;

// Detection prior: W [t - t_det; log(R_det^T R)]; d log / d w = 2 J_l^-1(log) R_det^T.
class DetectionPoseCost final : public ceres::SizedCostFunction<6, 7> {
 public:
  DetectionPoseCost(const Vec6& w, const Mat4& T_det)
      : w_(w), t_det_(T_det.topRightCorner<3, 1>()),
        q_det_(Mat3(T_det.topLeftCorner<3, 3>())) {
    q_det_.normalize();
  }
  bool Evaluate(double const* const* p, double* residuals, double** jac) const override {
    const Eigen::Quaterniond dq = q_det_.conjugate() * pose_quaternion(p[0]);
    const Vec3 phi = quaternion_log<double>(dq, nullptr);
    Eigen::Map<Vec6> r(residuals);
    r.head<3>() = w_.head<3>().cwiseProduct(Eigen::Map<const Vec3>(p[0]) - t_det_);
    r.tail<3>() = w_.tail<3>().cwiseProduct(phi);
    if (!jac || !jac[0]) return true;
    Mat6 J = Mat6::Zero();
    J.topLeftCorner<3, 3>() = w_.head<3>().asDiagonal();
    J.bottomRightCorner<3, 3>() = w_.tail<3>().asDiagonal() * 2.0 *
                                  geometry::so3_left_jacobian_inverse(phi) *
                                  q_det_.toRotationMatrix().transpose();
    tangent_to_ambient(J, p[0], jac[0]);
    return true;
  }

 private:
  Vec6 w_;
  Vec3 t_det_;
  Eigen::Quaterniond q_det_;
};

inline ConstantVelocityCost* make_constant_velocity_cost(const Mat6& Pi, double sigma_t,
                                                         double sigma_r) {
  return new ConstantVelocityCost(twist_weights(sigma_t, sigma_r).asDiagonal() * Pi);
}

inline DetectionTwistCost* make_detection_twist_cost(const Mat6& Pi, const Vec6& xi_d,
                                                     double sigma_t, double sigma_r,
                                                     double information_scale = 1.0) {
  return new RelativeTwistCost(
      twist_weights(sigma_t, sigma_r, information_scale).asDiagonal() * Pi, xi_d, -1.0);
}

// A twist measurement with a full covariance (e_reg weighed by GICP's information):
// r = L (xi_m - xi~(T_a, T_b)) with L^T L the pseudo-inverse of the covariance, so that a
// direction the covariance leaves out (zero variance: across the link) carries no weight and
// a Huber threshold is in sigmas; throws for a covariance that is not finite or has no
// positive variance.
inline Mat6 twist_sqrt_information(const Mat6& covariance) {
  if (!covariance.allFinite()) throw std::invalid_argument("twist measurement: covariance not finite");
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (covariance + covariance.transpose()));
  const double largest = eig.eigenvalues().maxCoeff();
  if (!(largest > 0)) throw std::invalid_argument("twist measurement: covariance without a positive variance");
  Mat6 L = Mat6::Zero();
  for (int k = 0; k < 6; ++k) {
    const double lambda = eig.eigenvalues()(k);
    // below this fraction of the largest: a direction the measurement does not speak of
    if (lambda > 1e-12 * largest) L.row(k) = eig.eigenvectors().col(k).transpose() / std::sqrt(lambda);
  }
  return L;
}

inline DetectionTwistCost* make_twist_measurement_cost(const Mat6& covariance, const Vec6& xi_m) {
  return new RelativeTwistCost(twist_sqrt_information(covariance), xi_m, -1.0);
}

inline DetectionPoseCost* make_detection_pose_cost(const Mat4& T_det, double sigma_t,
                                                   double sigma_r,
                                                   double information_scale = 1.0) {
  return new DetectionPoseCost(twist_weights(sigma_t, sigma_r, information_scale), T_det);
}

inline LinkCost* make_link_cost(const Mat6& Pi, double sigma_t, double sigma_r) {
  return new RelativeTwistCost(
      twist_weights(sigma_t, sigma_r).asDiagonal() * (Mat6::Identity() - Pi), Vec6::Zero(), 1.0);
}

}  // namespace twistslam::optim::detail
