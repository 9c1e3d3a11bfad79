#pragma once
// Sliding-window optimisation of one object's trajectory (paper eq. 9, object terms only):
// the poses T_w_o of the last N frames of a track, refined by
//   e_const  constant velocity: Pi (xi~_{i+1} - xi~_i), three consecutive poses;
//   e_det    detection twist:   Pi (xi_d_i - xi~_i),  xi_d_i = log(T_d(i+1) T_d(i)^-1) (eq. 5);
//   e_prior  detection pose:    [t_i - t_d(i); log(R_d(i)^T R_i)]  (anchors the canonical pose);
//   e_link   mechanical link:   (I - Pi) xi~_i, the motion the link forbids (a stiff prior);
// where xi~_i = log(T_w_o(i+1) T_w_o(i)^-1) is the twist linking consecutive poses (eq. 2,
// left-multiplied in the world frame). Each term is a Ceres cost of cpp/optim/object_costs.hpp
// added through the ProblemBuilder, the same families the full BA uses (docs/design.md).
// Public header: Eigen and std only.
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::optim {

// One frame of the window; consecutive entries are consecutive frames (a frame without a
// detection keeps its predicted pose as the initial value).
struct ObjectWindowFrame {
  Mat4 T_w_o = Mat4::Identity();      // initial estimate, refined in place
  bool fixed = false;                  // held constant (e.g. poses that left the window)
  bool has_detection = false;
  Mat4 T_w_o_detected = Mat4::Identity();  // the detected box pose in the tracking frame
  double detection_weight = 1.0;      // multiplies the information of this frame's detection terms
};

// Standard deviations: each residual is divided by its sigma (diagonal weights W = 1/sigma),
// then the Huber loss with threshold `huber_*` applies to the whitened squared norm.
struct ObjectWindowOptions {
  double const_sigma_translation = 0.3;  // m/frame, change of the translational twist
  double const_sigma_rotation = 0.03;    // rad/frame, change of the rotational twist
  double det_sigma_translation = 0.3;    // m, noise of a detection twist
  double det_sigma_rotation = 0.1;       // rad
  double prior_sigma_translation = 0.3;  // m, noise of a detected box centre
  double prior_sigma_rotation = 0.1;     // rad, noise of a detected box orientation
  double link_sigma_translation = 0.01;  // m/frame, out-of-link motion allowed
  double link_sigma_rotation = 0.002;    // rad/frame
  double huber_const = 3.0;              // whitened units (sigmas)
  double huber_det = 2.0;
  double huber_prior = 2.0;
  bool use_const = true;
  bool use_det_twist = true;
  bool use_prior = true;
  bool use_link = true;
  int max_iterations = 10;
  // Outlier gate (as in bundle_adjust): after a first pass, each detection term (prior,
  // e_det) whose whitened squared error exceeds this is removed and the window is solved
  // again (only if one was removed). 12.59: 95 % of chi2 with 6 dof, the quantile the BA's
  // gates use. <= 0: one pass, Huber only.
  double chi2_detection = 12.59;
};

struct ObjectWindowSummary {
  bool usable = false;  // Ceres produced a solution
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  int num_residuals = 0;
  int num_outliers = 0;  // detection terms removed by the chi2 gate
};

// Refines frames[i].T_w_o in place. Pi is the link's projector (geometry/link_projection.hpp).
// Fewer than two frames, or no residual at all: nothing to do (usable = false, poses kept).
ObjectWindowSummary optimize_object_window(std::vector<ObjectWindowFrame>& frames,
                                           const Mat6& Pi, const ObjectWindowOptions& options);

}  // namespace twistslam::optim
