#pragma once
// Private (Eigen only): Levenberg-Marquardt for the static bundle adjustment (e_stat of paper
// eq. 9: stereo / mono reprojections of world points in keyframe poses, Huber loss), with the
// points eliminated (Schur complement) and the reduced camera system solved by a dense
// Cholesky: what Ceres' DENSE_SCHUR does for this problem, by the same trust-region rules
// (Jacobi scaling from the first Jacobian, the Levenberg-Marquardt diagonal clamped to
// [1e-6, 1e32] and divided by the radius, the radius grown by 1 / max(1/3, 1 - (2 rho - 1)^3)
// on a step whose cost decrease is above 1e-3 of the model's and halved, then quartered, ...
// on a rejected one; the function and parameter tolerances stop without taking the step).
// Without Ceres' generic block machinery it runs the local BA several times faster
// (benchmarks/bench_ba.py has both); results agree to rounding (tests/cpp/optim/test_bundle_adjustment.cpp,
// BuiltinSchurLMFollowsCeresDenseSchur).
//
// The poses and points are the caller's parameter arrays, changed in place: a pose is
// [tx, ty, tz, qx, qy, qz, qw] (pose_parameterization.hpp; the tangent [v; w] moves t by v and
// left-multiplies q by [cos|w|, sin|w| w / |w|]), a point [x, y, z].
#include <string>
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::optim::detail {

struct SchurLMObservation {
  int pose = -1;              // index of add_pose
  int point = -1;             // index of add_point
  Vec3 z = Vec3::Zero();      // [u, v, u_right]; u_right < 0: a mono observation ([u, v])
  double sqrt_info = 1;       // 1 / sigma (px^-1)
  double huber_delta = 0;     // on the whitened error; <= 0: plain least squares
  double chi2_gate = 0;       // remove_gated_outliers' threshold; <= 0: never removed
};

struct SchurLMOptions {
  int max_iterations = 10;            // steps tried, taken or not (Ceres' count)
  double function_tolerance = 1e-6;   // |cost change| / cost that ends the solve
  double gradient_tolerance = 1e-10;  // max |gradient| that ends it
  double parameter_tolerance = 1e-8;  // |step| / (|x| + tol) that ends it
  double initial_trust_region_radius = 1e4;
};

struct SchurLMSummary {
  bool usable = false;  // a solution was computed (converged or out of iterations)
  int iterations = 0;   // as Ceres counts them: the initial state and every step tried
  double initial_cost = 0, final_cost = 0;
  std::string message;
};

class SchurLM {
 public:
  // `camera` must outlive the solver; min_depth (m): a point nearer to either image plane
  // cannot be evaluated (a step that puts one there is rejected; cheirality).
  SchurLM(const geometry::StereoCamera& camera, double min_depth);

  int add_pose(double* params7, bool fixed);
  int add_point(double* params3, bool fixed);
  // Throws std::invalid_argument for an index out of range.
  void add_observation(const SchurLMObservation& observation);

  // Refines the free poses and points in place. Not usable (nothing changed) when the initial
  // state cannot be evaluated or the reduced system fails five times in a row.
  SchurLMSummary solve(const SchurLMOptions& options);

  // Removes each gated observation whose squared whitened error (without the loss) exceeds
  // its chi2_gate or that cannot be evaluated (behind a camera). Returns the number removed.
  int remove_gated_outliers();

  int num_observations() const { return static_cast<int>(observations_.size()); }

 private:
  struct Linearization;
  double evaluate(const std::vector<double>& poses, const std::vector<double>& points,
                  Linearization* lin) const;

  const geometry::StereoCamera& camera_;
  double min_depth_;
  std::vector<double*> poses_, points_;
  std::vector<int> pose_free_, point_free_;  // index among the free blocks, -1: fixed
  int num_free_poses_ = 0, num_free_points_ = 0;
  std::vector<SchurLMObservation> observations_;
};

}  // namespace twistslam::optim::detail
