#pragma once
// Local bundle adjustment over a window of keyframes (paper eq. 9, static term e_stat for
// now): plain data in, refined in place. The map module fills a BAProblem from its keyframes
// (the local window free, covisible keyframes fixed) and reads poses, points and per
// observation outlier flags back. Public header: Eigen and std only; Ceres stays in the .cpp
// files. The object terms (e_dyna, e_const, e_reg, e_det, e_geo) plug into the same Ceres
// problem through the internal ProblemBuilder (problem_builder.hpp). See docs/optim.md.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::optim {

struct BAKeyframe {
  Mat4 T_c_w = Mat4::Identity();
  bool fixed = false;  // held constant (covisible keyframes outside the window, gauge)
};

struct BAPoint {
  Vec3 X_w = Vec3::Zero();
  bool fixed = false;
};

struct BAObservation {
  int keyframe = -1;      // index into BAProblem::keyframes
  int point = -1;         // index into BAProblem::points
  Vec2 uv = Vec2::Zero(); // left image pixel
  double u_right = -1;    // right image column; < 0: mono
  double inv_sigma2 = 1;  // 1 / sigma^2 of the keypoint's octave
};

// e_dyna of eq. 9 (optional): a moving object seen from the window's keyframes. Its pose
// at each keyframe's time, T_w_o, and its points X_o in the object frame are refined with
// the keyframes; its keypoints reproject through X_c = T_c_w T_w_o X_o. Consecutive poses
// are tied by the mechanical link (e_link: (I - Pi) log(T_b T_a^-1) = 0), which is what lets
// the dynamic points inform the camera: a free object pose would absorb any camera motion.
struct BAObjectPose {
  int keyframe = -1;  // index into BAProblem::keyframes: the camera that saw this pose
  Mat4 T_w_o = Mat4::Identity();
  bool fixed = false;
  int frame = -1;     // its frame index (e_const's frame gaps; -1: unknown, no e_const)
};

// e_det / e_reg of eq. 9 (optional): the object's motion between two of its poses a and b
// as a LiDAR sensor measured it, relative to the two cameras that saw them:
//   D = T_cb_o(b) T_ca_o(a)^-1 (camera a's frame to camera b's),
// from a pair of 3D boxes (eq. 5: D = T_cb_box(b) T_ca_box(a)^-1) or from the GICP
// registrations of the object scans chained over the frames between a and b (eq. 6-7).
// Its world motion is T_w_cb D T_ca_w, so the residual
//   W Pi (log(S T_w_cb D T_ca_w S^-1) - log(S T_w_o(b) T_w_o(a)^-1 S^-1))
// involves both cameras and both object poses. S moves the world origin to the object's
// initial position at pose a: a twist's v is the velocity of the point at the origin, and W
// (diagonal, m and rad over the interval) means what its sigmas say only near the object.
struct BAObjectMotion {
  int pose_a = -1, pose_b = -1;  // indices into the object's poses (a before b)
  Mat4 D = Mat4::Identity();
  double sigma_translation = 0.1;  // m
  double sigma_rotation = 0.01;    // rad
  double huber_delta = 0;          // in sigmas; <= 0: no loss
};

// The detection pose prior of eq. 9 for an object whose frame is its box frame (canonical):
// W [t_c_o - t_c_box; log(R_c_box^T R_c_o)] with T_c_o = T_c_w T_w_o, on the camera and the
// object pose.
struct BAObjectBox {
  int pose = -1;  // index into the object's poses
  Mat4 T_c_box = Mat4::Identity();
  double sigma_translation = 0.1;  // m
  double sigma_rotation = 0.01;    // rad
  double huber_delta = 0;          // in sigmas; <= 0: no loss
};

struct BAObject {
  std::vector<BAObjectPose> poses;  // in time order (the link ties poses k and k + 1)
  std::vector<Vec3> points_o;       // X_o
  Mat6 Pi = Mat6::Identity();       // the link's projector (geometry/link_projection.hpp)
  // LiDAR terms: they join only between poses that e_dyna already puts in the problem
  std::vector<BAObjectMotion> motions;
  std::vector<BAObjectBox> boxes;
  // e_const between three consecutive poses in the problem a, b, c (frames known, increasing):
  //   W Pi (log(S T_c T_b^-1 S^-1) / n_bc - log(S T_b T_a^-1 S^-1) / n_ab),
  // n the frame gaps, S the origin at the object's initial position at b; W from these per-frame
  // sigmas times sqrt((n_ab + n_bc) / 2) (the mean twists of longer intervals differ more).
  // 0: no e_const.
  double const_sigma_translation = 0;  // m/frame
  double const_sigma_rotation = 0;     // rad/frame
  double const_huber_delta = 0;        // in sigmas; <= 0: no loss
};

struct BADynamicObservation {
  int object = -1;        // index into BAProblem::objects
  int pose = -1;          // index into that object's poses (its keyframe is the camera)
  int point = -1;         // index into that object's points_o
  Vec2 uv = Vec2::Zero(); // left image pixel
  double u_right = -1;    // right image column; < 0: mono
  double inv_sigma2 = 1;  // 1 / sigma^2 of the keypoint's octave
};

struct BAProblem {
  std::vector<BAKeyframe> keyframes;
  std::vector<BAPoint> points;
  std::vector<BAObservation> observations;
  std::vector<BAObject> objects;                          // e_dyna; empty: static BA
  std::vector<BADynamicObservation> dynamic_observations;
};

enum class BALinearSolver {
  // a static problem with up to 100 free poses: kBuiltinDenseSchur; otherwise Ceres' dense
  // Schur for up to 100 free poses, its sparse Schur above
  kAuto,
  // Levenberg-Marquardt of our own with the points eliminated (optim/schur_lm.hpp), Ceres'
  // DENSE_SCHUR rules without its generic machinery; static problems only (with objects:
  // Ceres' dense Schur)
  kBuiltinDenseSchur,
  kDenseSchur,     // Ceres' DENSE_SCHUR
  kSparseSchur,
  kIterativeSchur,
};

struct BundleAdjustmentOptions {
  int max_iterations_first = 5;    // first pass, every valid observation, Huber loss
  int max_iterations_second = 10;  // second pass after the outliers are removed
  double huber_delta_stereo = std::sqrt(7.815);
  double huber_delta_mono = std::sqrt(5.991);
  // Whitened chi2 thresholds of the outlier test (after the first pass and at the end).
  double chi2_stereo = 7.815;
  double chi2_mono = 5.991;
  bool remove_outliers = true;  // false: one pass of first + second iterations, no removal
  int num_threads = 2;
  double min_depth = 0.1;  // m; closer points count as behind the camera
  BALinearSolver linear_solver = BALinearSolver::kAuto;
  double function_tolerance = 1e-6;  // Ceres' relative cost change for convergence
  // e_link between consecutive object poses: the out-of-link motion allowed (a stiff prior,
  // as the object window's; no loss: the link is a model, not a measurement)
  double link_sigma_translation = 0.01;  // m
  double link_sigma_rotation = 0.002;    // rad
  // Levenberg-Marquardt's first damping is 1 / radius (on the Jacobi-scaled normal
  // equations). Ceres' default 1e4 lets the first steps fling weakly constrained points
  // (far, mono) behind the cameras, and each rejected step costs an iteration.
  double initial_trust_region_radius = 10;
  // e_const between the objects' keyframe poses (BAObject::const_sigma_*); false: left out
  bool object_const = true;
};

struct BundleAdjustmentReport {
  // 0.5 * sum of Huber(chi2) over every valid observation (outliers included), at the
  // initial and the final state: the two are comparable.
  double initial_cost = 0, final_cost = 0;
  // RMS pixel error per image coordinate (u, v and u_right count separately) over the
  // observations that are inliers at the end, at the initial and the final state.
  double initial_rmse_px = 0, final_rmse_px = 0;
  int num_outliers = 0;
  // Per observation: 1 = outlier at the final state (chi2 above threshold, behind a camera,
  // or invalid: non-finite data, inv_sigma2 <= 0, non-finite pose or point).
  std::vector<std::uint8_t> outlier;
  // The same per dynamic observation (e_dyna); costs and RMS above are the static term's.
  std::vector<std::uint8_t> dynamic_outlier;
  int num_dynamic_residuals = 0;  // dynamic observations in the first pass
  int num_object_motions = 0;     // BAObjectMotion terms in the problem (e_det / e_reg)
  int num_object_boxes = 0;       // BAObjectBox terms in the problem
  int num_object_const = 0;       // e_const terms in the problem
  int iterations = 0;      // Ceres iterations over both passes
  double solve_ms = 0;     // wall time of the whole call
  bool converged = false;  // a usable solution was computed (false: nothing was changed)
  int num_residuals = 0;   // observations in the first pass
  std::string message;     // Ceres' termination message or the reason for not solving
};

// Refines the free keyframe poses and points of `problem` in place, and its objects' free
// poses and points. Throws std::invalid_argument if an observation indexes a keyframe,
// point, object, object pose or object point out of range;
// any other bad data (NaN, points behind the camera, no observations) gives outlier flags
// and, when nothing can be solved, converged = false with the problem unchanged.
BundleAdjustmentReport bundle_adjust(BAProblem& problem, const geometry::StereoCamera& cam,
                                     const BundleAdjustmentOptions& options = {});

}  // namespace twistslam::optim
