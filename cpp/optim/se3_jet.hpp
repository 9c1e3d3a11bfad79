#pragma once
// Private (Ceres): SE(3) logarithms of pose blocks, templated so that they run on doubles and
// on ceres::Jet (autodiff residual families: e_const, e_det, the detection prior, e_link).
//
// A pose block is [t, q] (pose_parameterization.hpp). The twist between two poses is
//   xi = log(T_b T_a^-1) = [J_l(w)^-1 t; w],   R = R_b R_a^T,  t = t_b - R t_a,
// the same quantity as geometry::twist_between(T_a, T_b) (paper eq. 2: T_b = exp(xi) T_a).
// The functions normalise the quaternions they read, so that the value does not depend on
// the scale of the 4 ambient coordinates (the manifold keeps them unit anyway; this makes the
// ambient Jacobians well defined for numerical checks and costs two square roots).
//
// Small angles: every closed form below that divides by the angle has a Taylor branch below
// kSmallSin (= sin(theta/2)), written in theta^2 / |vec q|^2 only, so that no square root of
// zero appears (its derivative would be infinite on Jets). The truncation error is below
// 1e-18 relative there, and the closed forms lose at most ~1e-10 to cancellation just above.
#include <ceres/jet.h>

#include <Eigen/Geometry>
#include <cmath>

namespace twistslam::optim::detail {

constexpr double kSmallSin = 1e-3;  // |vec(q)| = sin(theta / 2), i.e. theta < 2e-3 rad

// Unit quaternion of a pose block (Eigen order x, y, z, w at p + 3).
template <typename T>
Eigen::Quaternion<T> pose_quaternion(const T* p) {
  using std::sqrt;
  const Eigen::Quaternion<T> q(p[6], p[3], p[4], p[5]);
  return Eigen::Quaternion<T>(q.coeffs() / sqrt(q.squaredNorm()));
}

// Rotation vector (axis * angle, angle in [0, pi]) of a unit quaternion, i.e. so3_log of
// its rotation matrix. Also returns theta^2 for the caller's own series.
template <typename T>
Eigen::Matrix<T, 3, 1> quaternion_log(const Eigen::Quaternion<T>& q_in, T* theta2_out) {
  using std::atan2;
  using std::sqrt;
  // q and -q are the same rotation; w >= 0 picks the angle in [0, pi].
  const T sign = q_in.w() < T(0) ? T(-1) : T(1);
  const T w = sign * q_in.w();
  const Eigen::Matrix<T, 3, 1> v = sign * q_in.vec();
  const T s2 = v.squaredNorm();
  T f;  // theta / s, with theta = 2 atan2(s, w)
  if (s2 < T(kSmallSin * kSmallSin)) {
    // atan(x) / x = 1 - x^2/3 + x^4/5 - ..., x = s / w (w ~ 1 here)
    const T x2 = s2 / (w * w);
    f = T(2) / w * (T(1) - x2 / T(3) + x2 * x2 / T(5));
  } else {
    const T s = sqrt(s2);
    f = T(2) * atan2(s, w) / s;
  }
  if (theta2_out) *theta2_out = f * f * s2;
  return f * v;
}

// J_l(w)^-1 t for the SO(3) left Jacobian, J_l^-1 = I - hat(w)/2 + c hat(w)^2 with
// c = 1/theta^2 - cot(theta/2) / (2 theta) (Barfoot eq. 7.76; geometry::so3_left_jacobian_inverse).
template <typename T>
Eigen::Matrix<T, 3, 1> left_jacobian_inverse_times(const Eigen::Matrix<T, 3, 1>& w,
                                                   const T& theta2,
                                                   const Eigen::Matrix<T, 3, 1>& t) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  T c;
  if (theta2 < T(4 * kSmallSin * kSmallSin)) {
    // c = 1/12 + theta^2/720 + theta^4/30240 + theta^6/1209600 + O(theta^8)
    c = T(1.0 / 12.0) +
        theta2 * (T(1.0 / 720.0) + theta2 * (T(1.0 / 30240.0) + theta2 * T(1.0 / 1209600.0)));
  } else {
    const T theta = sqrt(theta2);
    const T half = T(0.5) * theta;
    c = T(1) / theta2 - cos(half) / (T(2) * theta * sin(half));
  }
  const Eigen::Matrix<T, 3, 1> wxt = w.cross(t);
  return t - T(0.5) * wxt + c * w.cross(wxt);
}

// xi = log(T_b T_a^-1) = twist_between(T_a, T_b) for two pose blocks; xi = [v; w].
template <typename T>
Eigen::Matrix<T, 6, 1> relative_twist(const T* pose_a, const T* pose_b) {
  const Eigen::Quaternion<T> qa = pose_quaternion(pose_a);
  const Eigen::Quaternion<T> qb = pose_quaternion(pose_b);
  const Eigen::Quaternion<T> q = qb * qa.conjugate();
  const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ta(pose_a), tb(pose_b);
  const Eigen::Matrix<T, 3, 1> t = tb - q * ta;
  T theta2;
  Eigen::Matrix<T, 6, 1> xi;
  xi.template tail<3>() = quaternion_log(q, &theta2);
  xi.template head<3>() = left_jacobian_inverse_times<T>(xi.template tail<3>(), theta2, t);
  return xi;
}

}  // namespace twistslam::optim::detail
