#pragma once
// SE(3) as 4x4 matrices with twists xi = [v; w] (translation part first, docs/design.md).
// Closed forms after Barfoot, "State Estimation for Robotics", sec. 7.1 (same ordering).
#include <string>

#include "geometry/types.hpp"

namespace twistslam::geometry {

Mat4 se3_exp(const Vec6& xi);
Vec6 se3_log(const Mat4& T);
Mat4 se3_inverse(const Mat4& T);

// Adjoint for [v; w] twists: exp(Ad(T) xi) = T exp(xi) T^-1.
Mat6 se3_adjoint(const Mat4& T);

// Left Jacobian: exp(xi + d) ~= exp(J_l(xi) d) exp(xi); right: J_r(xi) = J_l(-xi).
Mat6 se3_left_jacobian(const Vec6& xi);
Mat6 se3_left_jacobian_inverse(const Vec6& xi);
Mat6 se3_right_jacobian(const Vec6& xi);
Mat6 se3_right_jacobian_inverse(const Vec6& xi);

// Pose from rotation and translation, and the twist between two poses expressed in the
// frame of the left factor: the xi with T_b = exp(xi) T_a (paper eq. 2).
Mat4 make_pose(const Mat3& R, const Vec3& t);
Vec6 twist_between(const Mat4& T_a, const Mat4& T_b);

// Constant-velocity prediction of the next pose from the last two: the motion from
// T_previous to T_last applied once more, T_last T_previous^-1 T_last. The same formula holds
// for T_w_c and for T_c_w poses (the inverse of the one is the prediction of the other).
Mat4 predict_constant_velocity(const Mat4& T_previous, const Mat4& T_last);

// Checks that T is a rigid transform (finite; R^T R = I and last row 0 0 0 1 within tol,
// det R > 0). rigid_transform_problem says what is wrong (empty when nothing is).
bool is_rigid_transform(const Mat4& T, double tol = 1e-6);
std::string rigid_transform_problem(const Mat4& T, double tol);

}  // namespace twistslam::geometry
