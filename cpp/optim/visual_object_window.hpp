#pragma once
// Sliding-window refinement of one object cluster from its keypoints (paper eq. 9, the object
// terms of the local BA): the poses T_w_o of its last N frames and its points X_o, with the
// camera poses of those frames held fixed, refined by
//   e_dyna   reprojection of X_c = T_c_w T_w_o X_o against each observation (stereo or mono);
//   e_const  constant velocity Pi (xi~_{i+1} - xi~_i) over three consecutive poses;
//   e_link   (I - Pi) xi~_i, the motion the mechanical link forbids (a stiff prior),
//   e_det    Pi (xi_d - xi~_i), the twist between two consecutive 3D detections (eq. 5),
//            plus a weak prior on each detected pose (not in the paper: it anchors the
//            canonical pose the twists alone would let drift),
//   e_reg    Pi (xi_r - xi~_i), the motion GICP measured between consecutive object scans
//            (eq. 6-7),
// each a cost family of the ProblemBuilder (the ones the full BA and the detections
// tracker's window use). Frame-to-frame twists (eq. 4) are noisy where a car shows few
// corners; e_const is what smooths them (TwistSLAM). Public header: Eigen and std only.
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::optim {

struct VisualObjectObservation {
  int frame = 0;          // index into the window's frames
  int point = 0;          // index into the points
  Vec2 uv = Vec2::Zero(); // px, left image
  double u_right = -1;    // px; < 0: mono
  double inv_sigma2 = 1;  // pyramid level weight
};

struct VisualObjectWindow {
  std::vector<Mat4> T_c_w;   // camera pose per frame (fixed)
  std::vector<Mat4> T_w_o;   // object pose per frame, consecutive frames; refined in place
  std::vector<Vec3> X_o;     // points in the object frame; refined in place
  std::vector<VisualObjectObservation> observations;
  int num_fixed_frames = 1;  // leading poses held fixed (the gauge and the past)
  // >= 0: this pose is held fixed as well (the gauge of a whole track, where its leading
  // poses are the least settled; the object frame's points follow it)
  int gauge_frame = -1;
  // e_head: the travel axis in the object frame (zero: unknown, no term) and the road normal
  Vec3 travel_axis_o = Vec3::Zero();
  Vec3 up_w = Vec3(0, -1, 0);
  bool wheeled = false;  // a vehicle on the road: the axis-free e_head may apply (no axis yet)
  // LiDAR terms, one entry per frame or none: the associated detection's box pose T_w_det
  // (has_detection), and the motion M_w = T_w_o(i+1) T_w_o(i)^-1 registration measured
  // from frame i to i + 1 (has_registration[i]; the last entry is unused)
  std::vector<Mat4> T_w_det;
  std::vector<char> has_detection;
  std::vector<Mat4> M_w_reg;
  std::vector<char> has_registration;
  // its sigmas (m/frame, rad/frame) per entry, or none: the options' fixed sigmas
  std::vector<Vec2> reg_sigma;
  // or its whole covariance per entry (eps with M_w -> exp(eps) M_w, world twist at the world
  // origin; zero across the link), or none; a zero entry: the sigmas above
  std::vector<Mat6> reg_covariance;
};

struct VisualObjectWindowOptions {
  // e_dyna's sigmas (the observations' pyramid-level sigmas) times this: < 1 trusts the
  // keypoints more than the other terms, > 1 less
  double reprojection_sigma_scale = 1.0;
  double huber_stereo = 2.796;           // px, sqrt(chi2 3 dof 95 %) as the BA
  double huber_mono = 2.448;             // px, sqrt(chi2 2 dof 95 %)
  double const_sigma_translation = 0.05; // m/frame, change of the translational twist
  double const_sigma_rotation = 0.005;   // rad/frame, change of the rotational twist
  // > 0: below this step per frame (m, from the window's initial positions) the rotation
  // sigma shrinks in proportion to the step, to const_rotation_min_fraction of it at rest:
  // a vehicle's yaw rate is speed x curvature, and curvature changes along the path, so a
  // crawling car's yaw rate hardly changes from frame to frame. 0: one sigma for every speed
  double const_rotation_reference_step_m = 0;
  double const_rotation_min_fraction = 0.1;
  double link_sigma_translation = 0.01;  // m/frame, out-of-link motion allowed
  // rad/frame: 0.002 left 0.06-0.26 deg/m of roll / pitch in the object RPE_r; with 0.001
  // crowded seeds 0-2 went 0.34/0.35/0.37 -> 0.28/0.32/0.34 deg/m, urban 0.41/0.12/0.34 ->
  // 0.45/0.12/0.34 (0.0005: crowded 0.28/0.29/0.33, urban 0.46/0.13/0.34 and a ghost)
  double link_sigma_rotation = 0.001;
  double huber_const = 3.0;              // sigmas
  // > 0: e_rest, a prior of no motion on each step between consecutive poses (m/frame, the
  // translation only; no robust loss): most objects in a street are parked, and a track whose
  // few far points leave its motion unobserved keeps still instead of running with the noise
  // of its re-seeds. 0: off
  double rest_sigma_translation = 0;
  double lateral_sigma = 0.02;           // m/frame, e_head
  double huber_heading = 3.0;            // sigmas
  // e_det (eq. 9): sigmas of the twist between two detections, per frame. Box centres of a
  // LiDAR detector scatter by ~0.1-0.2 m and headings by a few degrees (the oracle detections
  // of the simulator by 0.1 m / 2 deg), so a twist from two of them by ~sqrt(2) of that
  double det_sigma_translation = 0.2;    // m/frame
  double det_sigma_rotation = 0.05;      // rad/frame
  double huber_det = 2.0;                // sigmas
  // > 0: beyond this range (m, box centre from the camera of its frame) every e_det and
  // detection-pose sigma grows in proportion to the range: a far car gives a detector fewer
  // points, so its box centre and heading scatter more. 0: one sigma at every range
  double det_sigma_reference_range_m = 0;
  // detection pose prior (not in the paper): a detection's box pose anchors the pose of its
  // frame; weak, so that the twists (visual, e_det, e_reg) keep the trajectory's shape
  double det_pose_sigma_translation = 0.3;  // m
  double det_pose_sigma_rotation = 0.1;     // rad
  // e_reg (eq. 9): sigmas of the registered motion between consecutive object scans; GICP of
  // car scans is good to ~1-3 cm and ~0.2 deg (benchmarks/bench_gicp.py)
  double reg_sigma_translation = 0.03;   // m/frame
  double reg_sigma_rotation = 0.005;     // rad/frame
  double huber_reg = 2.0;                // sigmas
  bool use_detection_twist = true;
  bool use_detection_pose = true;
  bool use_registration = true;
  bool use_const = true;
  bool use_link = true;
  bool use_heading = true;               // e_head where the window has a travel axis
  // > 0: where it has none, the axis-free e_head on each triple of consecutive poses whose
  // two steps (from the initial positions) are at least this long (m/frame); 0: off
  double axis_free_heading_min_step_m = 0;
  // > 0: each of its two displacements spans as many frames as it takes to be at least this
  // long (m), so that the direction of a chord is long against the positions' noise (the
  // residual's noise is the positions', its yaw signal grows with the chord); 0: one frame
  double axis_free_heading_min_chord_m = 0;
  bool refine_points = true;
  int max_iterations = 5;
  // Ceres stops once an iteration changes the cost by less than this fraction of it
  double function_tolerance = 1e-6;
  double min_depth = 0.1;                // m
  // Windows of up to 50 frames run the built-in Levenberg-Marquardt (optim/block_lm.hpp:
  // Ceres' DENSE_SCHUR steps on the same residuals, without its solver's overhead); false,
  // or a longer window (the final smoothing of a long track), Ceres' dense / sparse Schur
  bool builtin_solver = true;
};

struct VisualObjectWindowSummary {
  bool usable = false;
  int iterations = 0;
  int num_residuals = 0;
  double initial_cost = 0, final_cost = 0;
};

// Pi: the link's projector. Fewer than two frames or no free pose: nothing is done.
VisualObjectWindowSummary refine_visual_object_window(const geometry::StereoCamera& camera,
                                                      VisualObjectWindow& window, const Mat6& Pi,
                                                      const VisualObjectWindowOptions& options);

}  // namespace twistslam::optim
