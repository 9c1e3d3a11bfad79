#include "geometry/se3.hpp"

#include <string>

#include <Eigen/LU>
#include <cmath>

#include "geometry/so3.hpp"

namespace twistslam::geometry {
namespace {

constexpr double kSmallAngle = 1e-4;  // rad; Taylor series below (see so3.cpp)

// Barfoot's Q(rho, phi): the off-diagonal block of the SE(3) left Jacobian.
Mat3 q_block(const Vec3& rho, const Vec3& phi) {
  const double t2 = phi.squaredNorm();
  const double t = std::sqrt(t2);
  double c1, c2, c3;
  if (t < kSmallAngle) {
    c1 = 1.0 / 6.0 - t2 / 120.0;
    c2 = 1.0 / 24.0 - t2 / 720.0;
    c3 = 1.0 / 120.0 - t2 / 2520.0;
  } else {
    const double s = std::sin(t), c = std::cos(t);
    c1 = (t - s) / (t2 * t);
    c2 = (t2 + 2.0 * c - 2.0) / (2.0 * t2 * t2);
    c3 = (2.0 * t - 3.0 * s + t * c) / (2.0 * t2 * t2 * t);
  }
  const Mat3 P = hat(phi);
  const Mat3 R = hat(rho);
  const Mat3 PR = P * R, RP = R * P, PRP = P * R * P;
  return 0.5 * R + c1 * (PR + RP + PRP) + c2 * (P * PR + RP * P - 3.0 * PRP) +
         c3 * (PRP * P + P * PRP);
}

}  // namespace

Mat4 make_pose(const Mat3& R, const Vec3& t) {
  Mat4 T = Mat4::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = t;
  return T;
}

Mat4 se3_exp(const Vec6& xi) {
  const Vec3 v = xi.head<3>(), w = xi.tail<3>();
  return make_pose(so3_exp(w), so3_left_jacobian(w) * v);
}

Vec6 se3_log(const Mat4& T) {
  const Vec3 w = so3_log(T.topLeftCorner<3, 3>());
  Vec6 xi;
  xi.head<3>() = so3_left_jacobian_inverse(w) * T.topRightCorner<3, 1>();
  xi.tail<3>() = w;
  return xi;
}

Mat4 se3_inverse(const Mat4& T) {
  const Mat3 Rt = T.topLeftCorner<3, 3>().transpose();
  return make_pose(Rt, -Rt * T.topRightCorner<3, 1>());
}

Mat6 se3_adjoint(const Mat4& T) {
  const Mat3 R = T.topLeftCorner<3, 3>();
  Mat6 A = Mat6::Zero();
  A.topLeftCorner<3, 3>() = R;
  A.topRightCorner<3, 3>() = hat(T.topRightCorner<3, 1>()) * R;
  A.bottomRightCorner<3, 3>() = R;
  return A;
}

Mat6 se3_left_jacobian(const Vec6& xi) {
  const Vec3 v = xi.head<3>(), w = xi.tail<3>();
  const Mat3 J = so3_left_jacobian(w);
  Mat6 out = Mat6::Zero();
  out.topLeftCorner<3, 3>() = J;
  out.topRightCorner<3, 3>() = q_block(v, w);
  out.bottomRightCorner<3, 3>() = J;
  return out;
}

Mat6 se3_left_jacobian_inverse(const Vec6& xi) {
  const Vec3 v = xi.head<3>(), w = xi.tail<3>();
  const Mat3 Jinv = so3_left_jacobian_inverse(w);
  Mat6 out = Mat6::Zero();
  out.topLeftCorner<3, 3>() = Jinv;
  out.topRightCorner<3, 3>() = -Jinv * q_block(v, w) * Jinv;
  out.bottomRightCorner<3, 3>() = Jinv;
  return out;
}

Mat6 se3_right_jacobian(const Vec6& xi) { return se3_left_jacobian(-xi); }

Mat6 se3_right_jacobian_inverse(const Vec6& xi) { return se3_left_jacobian_inverse(-xi); }

Vec6 twist_between(const Mat4& T_a, const Mat4& T_b) {
  return se3_log(T_b * se3_inverse(T_a));
}

Mat4 predict_constant_velocity(const Mat4& T_previous, const Mat4& T_last) {
  return T_last * se3_inverse(T_previous) * T_last;
}

std::string rigid_transform_problem(const Mat4& T, double tol) {
  if (!T.allFinite()) return "contains NaN or Inf";
  const double last_row = (T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff();
  if (!(last_row <= tol)) return "last row is not [0, 0, 0, 1]";
  return rotation_problem(T.topLeftCorner<3, 3>(), tol);
}

bool is_rigid_transform(const Mat4& T, double tol) { return rigid_transform_problem(T, tol).empty(); }

}  // namespace twistslam::geometry
