#include "objects/motion_uncertainty.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"

namespace twistslam::objects {
namespace {

// eigenvalues of a block below this fraction of its largest are directions the link forbids
// (zero up to rounding), never raised to a floor
constexpr double kLinkNullFraction = 1e-9;

double largest_eigenvalue(const Mat3& C) {
  const double v = Eigen::SelfAdjointEigenSolver<Mat3>(C, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  return std::max(v, 0.0);
}

// [v; w] at the world origin -> [v - c x w; w], the twist seen at the centre c
Mat6 to_centre(const Vec3& centre_w) {
  Mat6 A = Mat6::Identity();
  A.topRightCorner<3, 3>() = -geometry::hat(centre_w);
  return A;
}

// Cov(eps), eps the world twist moving M_w, restricted to the link
Mat6 motion_covariance_at_origin(const Mat6& information, const Mat4& M_w, const Mat6& Pi) {
  // a tiny ridge keeps an unseen direction finite: its variance becomes ~1e9 / trace(H)
  const double ridge = 1e-9 * std::max(information.trace(), 1e-12);
  const Mat6 C_delta = (information + ridge * Mat6::Identity()).ldlt().solve(Mat6::Identity());
  const Mat6 Ad = geometry::se3_adjoint(M_w);
  return Pi * Ad * C_delta * Ad.transpose() * Pi.transpose();
}

// The variance a symmetric 3x3 block needs added so that each of its (non-null) eigen-
// directions reaches min_sigma^2.
Mat3 floor_raise(const Mat3& block, double min_sigma) {
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (block + block.transpose()));
  const double largest = std::max(eig.eigenvalues().maxCoeff(), 0.0);
  Mat3 raise = Mat3::Zero();
  for (int k = 0; k < 3; ++k) {
    const double lambda = eig.eigenvalues()(k);
    if (!(lambda > kLinkNullFraction * largest) || !(largest > 0)) continue;
    const double missing = min_sigma * min_sigma - lambda;
    if (missing > 0) raise += missing * eig.eigenvectors().col(k) * eig.eigenvectors().col(k).transpose();
  }
  return raise;
}

}  // namespace

MotionSigmas registered_motion_sigmas(const Mat6& information, const Mat4& M_w, const Mat6& Pi,
                                      const Vec3& centre_w) {
  const Mat6 A = to_centre(centre_w);
  const Mat6 C = A * motion_covariance_at_origin(information, M_w, Pi) * A.transpose();
  MotionSigmas out;
  out.translation_m = std::sqrt(largest_eigenvalue(C.topLeftCorner<3, 3>()));
  out.rotation_rad = std::sqrt(largest_eigenvalue(C.bottomRightCorner<3, 3>()));
  return out;
}

Mat6 registered_motion_covariance(const Mat6& information, const Mat4& M_w, const Mat6& Pi,
                                  const Vec3& centre_w, const MotionCovarianceOptions& o) {
  const Mat6 A = to_centre(centre_w);
  Mat6 C = A * motion_covariance_at_origin(information, M_w, Pi) * A.transpose();
  Vec6 scale;
  scale << Vec3::Constant(o.scale_translation), Vec3::Constant(o.scale_rotation);
  C = scale.asDiagonal() * C * scale.asDiagonal();
  // adding a positive semi-definite block to each diagonal block keeps C positive semi-definite
  C.topLeftCorner<3, 3>() += floor_raise(C.topLeftCorner<3, 3>(), o.min_sigma_translation);
  C.bottomRightCorner<3, 3>() += floor_raise(C.bottomRightCorner<3, 3>(), o.min_sigma_rotation);
  const Mat6 A_inv = to_centre(-centre_w);  // [v_c; w] -> [v_c + c x w; w]
  const Mat6 C_w = A_inv * C * A_inv.transpose();
  return 0.5 * (C_w + C_w.transpose());
}

}  // namespace twistslam::objects
