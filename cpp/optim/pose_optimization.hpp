#pragma once
// Pose-only optimisation (camera tracking, paper eq. 3): the pose T_c_w that minimises the
// Huber-robustified reprojection error of known world points, with outlier rejection over
// several rounds. Public header: Eigen and std only (the solver is a dense 6-DoF
// Levenberg-Marquardt, no Ceres). See docs/optim.md.
#include <cmath>
#include <cstdint>
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::optim {

// One observation of a 3D point by a stereo (or mono) keypoint of the left image.
struct StereoObservation {
  Vec3 point_w = Vec3::Zero();  // point in the world frame
  Vec2 uv = Vec2::Zero();       // left image pixel
  double u_right = -1;          // right image column of the same keypoint; < 0: mono
  double inv_sigma2 = 1;        // information weight 1 / sigma^2 (sigma = scale of the octave)
  bool is_stereo() const { return u_right >= 0; }
};

struct PoseOptimizationOptions {
  int rounds = 4;                // optimise, re-classify inliers, repeat
  int iterations_per_round = 10; // Levenberg-Marquardt iterations per round
  // Whitened chi2 = inv_sigma2 * |error|^2 above which an observation is an outlier
  // (95 % quantiles of chi2 with 3 and 2 degrees of freedom).
  double chi2_stereo = 7.815;
  double chi2_mono = 5.991;
  // Huber thresholds on the whitened error norm.
  double huber_delta_stereo = std::sqrt(7.815);
  double huber_delta_mono = std::sqrt(5.991);
  // Points closer than this (m, along the optical axes of both cameras) count as behind.
  double min_depth = 0.1;
  // Fewer final inliers than this: the pose is not trusted (converged = false, initial pose
  // returned). Rounds stop early once fewer inliers than this remain.
  int min_inliers = 10;
};

struct PoseOptimizationResult {
  Mat4 T_c_w = Mat4::Identity();   // optimised pose, or the initial one if !converged
  std::vector<std::uint8_t> inlier;  // per observation, 1 = inlier after the last round
  int num_inliers = 0;
  double final_cost = 0;  // 0.5 * sum of Huber(chi2) over the final inliers
  bool converged = false; // finite pose supported by >= min_inliers inliers
  int iterations = 0;     // LM iterations over all rounds
};

// Never throws on data: an empty list, non-finite values, inv_sigma2 <= 0 or points behind
// the camera only make observations invalid (inlier = 0); a non-finite or non-rigid initial
// pose gives converged = false with the initial pose returned.
PoseOptimizationResult optimize_pose(const Mat4& T_c_w_init,
                                     const std::vector<StereoObservation>& obs,
                                     const geometry::StereoCamera& cam,
                                     const PoseOptimizationOptions& options = {});

}  // namespace twistslam::optim
