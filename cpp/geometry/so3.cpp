#include "geometry/so3.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <Eigen/LU>
#include <cmath>

#include "options/option_range.hpp"

namespace twistslam::geometry {
namespace {
// Below this angle (rad) the closed forms lose digits to cancellation, so we switch to the
// Taylor series; truncation error there is O(theta^4) ~ 1e-16 relative.
constexpr double kSmallAngle = 1e-4;
}  // namespace

Mat3 hat(const Vec3& a) {
  Mat3 A;
  A << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return A;
}

Vec3 vee(const Mat3& A) { return Vec3(A(2, 1), A(0, 2), A(1, 0)); }

std::string rotation_problem(const Mat3& R, double tol) {
  if (!R.allFinite()) return "contains NaN or Inf";
  const double orthogonality = (R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (!(orthogonality <= tol)) return "R^T R differs from I by " + options::format_number(orthogonality);
  // R^T R = I leaves det R = +-1: only the sign is left to check
  if (R.determinant() < 0) return "det R = -1 (a reflection)";
  return {};
}

Mat3 so3_exp(const Vec3& w) {
  const double theta2 = w.squaredNorm();
  const double theta = std::sqrt(theta2);
  double a, b;  // R = I + a hat(w) + b hat(w)^2
  if (theta < kSmallAngle) {
    a = 1.0 - theta2 / 6.0;
    b = 0.5 - theta2 / 24.0;
  } else {
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / theta2;
  }
  const Mat3 W = hat(w);
  return Mat3::Identity() + a * W + b * W * W;
}

Vec3 so3_log(const Mat3& R) {
  // Through the unit quaternion: Eigen's conversion (Shepperd's method) stays accurate near
  // pi where the trace formula divides by sin(theta) ~ 0.
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // angle in [0, pi]
  const Vec3 v = q.vec();
  const double s = v.norm();
  if (s < 1e-10) {
    // theta = 2 atan(s / w) ~= 2 s / w (1 - s^2 / (3 w^2))
    return (2.0 / q.w()) * (1.0 - s * s / (3.0 * q.w() * q.w())) * v;
  }
  const double theta = 2.0 * std::atan2(s, q.w());
  return (theta / s) * v;
}

Mat3 so3_left_jacobian(const Vec3& w) {
  const double theta2 = w.squaredNorm();
  const double theta = std::sqrt(theta2);
  double b, c;  // J = I + b hat(w) + c hat(w)^2
  if (theta < kSmallAngle) {
    b = 0.5 - theta2 / 24.0;
    c = 1.0 / 6.0 - theta2 / 120.0;
  } else {
    b = (1.0 - std::cos(theta)) / theta2;
    c = (theta - std::sin(theta)) / (theta2 * theta);
  }
  const Mat3 W = hat(w);
  return Mat3::Identity() + b * W + c * W * W;
}

Mat3 so3_left_jacobian_inverse(const Vec3& w) {
  const double theta2 = w.squaredNorm();
  const double theta = std::sqrt(theta2);
  double c;  // J^-1 = I - hat(w)/2 + c hat(w)^2, c = 1/theta^2 - cot(theta/2) / (2 theta)
  if (theta < kSmallAngle) {
    c = 1.0 / 12.0 + theta2 / 720.0;
  } else {
    const double half = 0.5 * theta;
    c = 1.0 / theta2 - std::cos(half) / (2.0 * theta * std::sin(half));
  }
  const Mat3 W = hat(w);
  return Mat3::Identity() - 0.5 * W + c * W * W;
}

Mat3 so3_right_jacobian(const Vec3& w) { return so3_left_jacobian(-w); }

Mat3 so3_right_jacobian_inverse(const Vec3& w) { return so3_left_jacobian_inverse(-w); }

Mat3 so3_orthonormalize(const Mat3& M) {
  Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

}  // namespace twistslam::geometry
