#pragma once
// SO(3) exponential / logarithm and Jacobians in closed form, stable at tiny angles and near pi.
#include <string>

#include "geometry/types.hpp"

namespace twistslam::geometry {

// Skew-symmetric matrix: hat(a) * b = a x b.
Mat3 hat(const Vec3& a);
Vec3 vee(const Mat3& A);

// Rodrigues' formula; w is the rotation vector (axis * angle, rad).
Mat3 so3_exp(const Vec3& w);
// Rotation vector with angle in [0, pi]; R must be a rotation (not checked here).
Vec3 so3_log(const Mat3& R);

// Left Jacobian: exp(w + d) ~= exp(J_l(w) d) exp(w). Right: J_r(w) = J_l(-w).
Mat3 so3_left_jacobian(const Vec3& w);
Mat3 so3_left_jacobian_inverse(const Vec3& w);
Mat3 so3_right_jacobian(const Vec3& w);
Mat3 so3_right_jacobian_inverse(const Vec3& w);

// Empty when R is a rotation (R^T R = I within tol, det R > 0), otherwise what is
// wrong: "R^T R differs from I by 2", "det R = -1 (a reflection)", "contains NaN or Inf".
std::string rotation_problem(const Mat3& R, double tol);

// Nearest rotation (SVD projection), used to clean up matrices read from text files.
Mat3 so3_orthonormalize(const Mat3& M);

}  // namespace twistslam::geometry
