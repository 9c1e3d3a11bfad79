#include "objects/motion_uncertainty.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"

namespace twistslam::objects {
namespace {

double largest_eigenvalue(const Mat3& C) {
  const double v = Eigen::SelfAdjointEigenSolver<Mat3>(C, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  return std::max(v, 0.0);
}

}  // namespace

MotionSigmas registered_motion_sigmas(const Mat6& information, const Mat4& M_w, const Mat6& Pi,
                                      const Vec3& centre_w) {
  // a tiny ridge keeps an unseen direction finite: its variance becomes ~1e9 / trace(H)
  const double ridge = 1e-9 * std::max(information.trace(), 1e-12);
  const Mat6 C_delta = (information + ridge * Mat6::Identity()).ldlt().solve(Mat6::Identity());
  const Mat6 Ad = geometry::se3_adjoint(M_w);
  const Mat6 C = Pi * Ad * C_delta * Ad.transpose() * Pi.transpose();
  Eigen::Matrix<double, 3, 6> at_centre;
  at_centre << Mat3::Identity(), -geometry::hat(centre_w);
  MotionSigmas out;
  out.translation_m = std::sqrt(largest_eigenvalue(at_centre * C * at_centre.transpose()));
  out.rotation_rad = std::sqrt(largest_eigenvalue(C.bottomRightCorner<3, 3>()));
  return out;
}

}  // namespace twistslam::objects
