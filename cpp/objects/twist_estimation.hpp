#pragma once
// Object twist estimation from keypoints (TwistSLAM "Dynamic object tracking", paper eq. 4):
//   E(xi) = sum_j rho(|z_j - proj(T_c_w exp(Pi xi) T_w_o_prev X_o_j)|_{Sigma_j^-1}),
// solved by Levenberg-Marquardt inside range(Pi) (the twists the mechanical link allows),
// Huber rho, and Sigma_j = sigma^2 / inv_sigma2_j with sigma from the median absolute deviation
// of the residuals (Malis & Vargas). The new object pose is T_w_o = exp(Pi xi) T_w_o_prev (eq. 2).
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::objects {

struct TwistObservation {
  Vec3 X_o = Vec3::Zero();  // m, the point in the object frame
  Vec2 uv = Vec2::Zero();   // px, its keypoint in the current left image
  double u_right = -1;      // px, column in the right image; < 0: mono observation
  double inv_sigma2 = 1;    // 1 / sigma_level^2 of the keypoint's octave (tracking/level_weights.hpp)
};

struct TwistEstimationOptions {
  int max_iterations = 30;       // LM iterations, first stage (all points, Huber); ~10 suffice
  int refine_iterations = 10;    // LM iterations, second stage on the chi2 inliers only
  double huber_k = 1.345;        // robust sigmas; Huber's 95 % efficiency under Gaussian noise
  double min_sigma_px = 0.5;     // px; MAD scale floor: keypoints are not located better than this
  double max_sigma_px = 5.0;     // px; a larger robust scale means most matches are wrong: fail
  double inlier_chi2_stereo = 7.815;  // chi2 (3 dof) at 95 %, in robust-sigma units
  double inlier_chi2_mono = 5.991;    // chi2 (2 dof) at 95 %
  int min_inliers = 10;          // fewer cannot tell a rigid motion from noise (ORB-SLAM's pose test)
  double min_depth = 0.1;        // m; points closer to an image plane are left out (not predicted)
  double initial_lambda = 1e-4;  // LM damping relative to diag(J^T W J), Marquardt's scaling
  double step_tolerance = 1e-6;  // m and rad; stop when the LM step is smaller (um, urad)
};

struct TwistEstimate {
  bool valid = false;
  std::string failure;          // empty when valid, else why ("too few inliers: 4 < 10", ...)
  Vec6 xi = Vec6::Zero();       // [v; w], log(T_w_o * T_w_o_prev^-1), lies in range(Pi)
  Mat4 T_w_o = Mat4::Identity();  // exp(xi) T_w_o_prev
  Mat6 covariance = Mat6::Zero();  // of xi (left perturbation), from the robust sigma; rank dof
  double sigma_px = 0;          // robust (MAD) residual scale at the solution, px at level 0
  std::vector<std::uint8_t> inlier;  // one flag per observation (chi2 test in sigma units)
  int num_inliers = 0;
  int iterations = 0;           // LM iterations of both stages
  double final_rms_px = 0;      // RMS of the inliers' weighted residual components, px
};

// Throws std::invalid_argument for bad options; data problems (too few observations or
// inliers, non-finite input, Pi not an orthogonal projector, divergence) give valid = false.
// xi_init is projected onto range(Pi) before use (zero or a constant-velocity guess).
TwistEstimate estimate_object_twist(const geometry::StereoCamera& camera, const Mat4& T_c_w,
                                    const Mat4& T_w_o_prev, const Mat6& Pi,
                                    const std::vector<TwistObservation>& observations,
                                    const Vec6& xi_init,
                                    const TwistEstimationOptions& options = {});

}  // namespace twistslam::objects
