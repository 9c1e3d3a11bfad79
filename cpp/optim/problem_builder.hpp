#pragma once
// Private (Ceres): one Ceres problem that every residual family of the BA (paper eq. 9) adds
// itself to. Included by this module's .cpp files only.
//
//   ProblemBuilder b;
//   int kf = b.add_pose(T_c_w, /*fixed=*/false);          // 7-vector, R^3 x SO(3)
//   int pt = b.add_point(X_w, false);                     // 3-vector, eliminated by Schur
//   auto id = b.add_stereo_reprojection(kf, pt, cam, uv, u_right, inv_sigma2, delta, 0.1);
//   b.gate(id, 7.815);                                    // chi2 outlier test between passes
//   b.solve(first); b.remove_gated_outliers(); b.solve(second);
//
// A later family (e_dyna, e_const, e_det, e_reg, e_geo) adds its blocks with add_pose /
// add_point / add_vector (object poses T_w_o, twists, object-frame points) and its residuals
// with add_residual(cost, loss, {blocks...}) -- or a dedicated add_xxx() next to
// add_stereo_reprojection -- and the same two-pass solve, outlier gating and Schur ordering
// apply: blocks marked `eliminate` (points) form the first elimination group.
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"
#include "optim/block_lm.hpp"
#include "optim/bundle_adjustment.hpp"
#include "optim/schur_lm.hpp"

namespace twistslam::optim::detail {

struct SolveOptions {
  int max_iterations = 10;
  int num_threads = 2;
  BALinearSolver linear_solver = BALinearSolver::kAuto;
  double function_tolerance = 1e-6;
  double initial_trust_region_radius = 10;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  // Set: this solver (e.g. DENSE_NORMAL_CHOLESKY for the object window: a few poses, no
  // eliminated blocks) and no Schur ordering; unset: `linear_solver` decides (the BA).
  std::optional<ceres::LinearSolverType> linear_solver_override;
};

// usable: a solution was produced (converged or ran out of iterations); the built-in
// solver's summary (schur_lm.hpp) is the same struct
using SolveSummary = SchurLMSummary;

// The built-in solvers' (schur_lm.hpp, block_lm.hpp) options from these
SchurLMOptions builtin_options(const SolveOptions& options);

class ProblemBuilder {
 public:
  ProblemBuilder();
  ~ProblemBuilder();
  ProblemBuilder(const ProblemBuilder&) = delete;
  ProblemBuilder& operator=(const ProblemBuilder&) = delete;

  // Parameter blocks; the builder owns their storage (stable addresses). Each returns a
  // block handle for the add_* functions below.
  //
  // Reproducibility: Ceres orders the blocks of an elimination group by address, and that
  // order decides the summation order of the Schur complement (a different order moved
  // poses by ~1e-14 m between identical calls). Blocks are carved out of one contiguous
  // buffer in insertion order, so address order is insertion order as long as they fit:
  // call reserve() with the total size first (blocks beyond it still work, in a new buffer
  // whose address, and so order, is up to the heap). Bit-identical also needs one thread:
  // Ceres' threaded evaluation and elimination sum in scheduling order.
  void reserve(int num_doubles);
  // From now on (call it first) blocks get their storage here but are not handed to Ceres,
  // and residuals are kept for solve() to run the built-in Levenberg-Marquardt
  // (block_lm.hpp) instead of Ceres' solver -- or for a solver of the caller's own on the
  // builder's parameters (SchurLM, schur_lm.hpp). pose(), point(), data() work as before;
  // gate() is refused (no outlier gating there).
  void keep_blocks_out_of_ceres() { blocks_in_ceres_ = false; }
  int add_pose(const Mat4& T, bool fixed);
  int add_point(const Vec3& X, bool fixed);
  // A generic Euclidean block (twist, size, ...); `eliminate` puts it in the Schur
  // elimination group (only for blocks that, like points, never share a residual with
  // another eliminated block).
  int add_vector(const double* values, int size, bool fixed, bool eliminate = false);

  int num_blocks() const { return static_cast<int>(blocks_.size()); }
  double* data(int block) { return blocks_[block].data; }
  int size(int block) const { return blocks_[block].size; }
  Mat4 pose(int block) const;
  Vec3 point(int block) const;

  // Huber loss on the squared whitened error, shared and owned by the builder; nullptr for
  // delta <= 0 (plain least squares).
  ceres::LossFunction* huber(double delta);

  // e_stat: stereo (u_right >= 0) or mono reprojection of point block `point` in pose block
  // `pose` (T_c_w). `cam` must outlive the builder.
  ceres::ResidualBlockId add_stereo_reprojection(int pose, int point,
                                                 const geometry::StereoCamera& cam,
                                                 const Vec2& uv, double u_right,
                                                 double inv_sigma2, double huber_delta,
                                                 double min_depth);

  // Object terms of eq. 9 (object_costs.hpp) on object pose blocks T_w_o; Pi is the link's
  // projector, sigmas are in metres / radians (per frame for twists), huber_delta in sigmas
  // (<= 0: no loss). information_scale multiplies W^2 (a detection's confidence). Throw
  // std::invalid_argument for a sigma <= 0.
  //   e_const:  W Pi (log(T_c T_b^-1) - log(T_b T_a^-1))      (a, b, c consecutive frames)
  //   e_det:    W Pi (xi_d - log(T_b T_a^-1)), xi_d = log(T_det_b T_det_a^-1) (eq. 5)
  //   prior:    W [t - t_det; log(R_det^T R)]
  //   e_link:   W (I - Pi) log(T_b T_a^-1), no loss: the link is a model, not a measurement
  ceres::ResidualBlockId add_constant_velocity(int pose_a, int pose_b, int pose_c,
                                               const Mat6& Pi, double sigma_t, double sigma_r,
                                               double huber_delta);
  ceres::ResidualBlockId add_detection_twist(int pose_a, int pose_b, const Mat6& Pi,
                                             const Vec6& xi_d, double sigma_t, double sigma_r,
                                             double huber_delta, double information_scale = 1.0);
  // A measured twist xi_m from pose a to pose b with its full covariance (object_costs.hpp's
  // twist measurement: e_reg weighed by GICP's information; zero variance = no weight there).
  ceres::ResidualBlockId add_twist_measurement(int pose_a, int pose_b, const Vec6& xi_m,
                                               const Mat6& covariance, double huber_delta);
  ceres::ResidualBlockId add_detection_pose(int pose, const Mat4& T_det, double sigma_t,
                                            double sigma_r, double huber_delta,
                                            double information_scale = 1.0);
  ceres::ResidualBlockId add_link(int pose_a, int pose_b, const Mat6& Pi, double sigma_t,
                                  double sigma_r);
  // Non-holonomic heading prior (heading_cost.hpp): the measured displacement d_w between
  // object pose blocks a and b has no component across their travel axis axis_o (object
  // frame, in the plane of normal up_w); pulls the rotations only. sigma_m in metres per
  // frame, huber_delta in sigmas.
  ceres::ResidualBlockId add_heading(int pose_a, int pose_b, const Vec3& axis_o,
                                     const Vec3& up_w, const Vec3& d_w, double sigma_m,
                                     double huber_delta);
  // The same without a known axis, on three consecutive object pose blocks: the measured
  // displacements d1_w (a -> b) and d2_w (b -> c) point the same way in the object frame
  // (heading_cost.hpp). sigma_m in metres per frame, huber_delta in sigmas.
  ceres::ResidualBlockId add_axis_free_heading(int pose_a, int pose_b, int pose_c,
                                               const Vec3& up_w, const Vec3& d1_w,
                                               const Vec3& d2_w, double sigma_m,
                                               double huber_delta);

  // e_dyna (dynamic_reprojection_cost.hpp): stereo (u_right >= 0) or mono reprojection of
  // the object-frame point block `object_point` (X_o) through the object pose block
  // `object_pose` (T_w_o, as the object window stores it) and the camera pose block
  // `camera_pose` (T_c_w, as the BA stores keyframes): X_c = T_c_w T_w_o X_o. Both poses in
  // one world frame. Weighting, Huber, min_depth and gating exactly as e_stat; `cam` must
  // outlive the builder.
  ceres::ResidualBlockId add_dynamic_reprojection(int camera_pose, int object_pose,
                                                  int object_point,
                                                  const geometry::StereoCamera& cam,
                                                  const Vec2& uv, double u_right,
                                                  double inv_sigma2, double huber_delta,
                                                  double min_depth);

  // Any other residual family: takes ownership of `cost`; `loss` from huber() (or owned
  // elsewhere, never taken over).
  ceres::ResidualBlockId add_residual(ceres::CostFunction* cost, ceres::LossFunction* loss,
                                      const std::vector<int>& blocks);

  // Outlier gating: after a pass, remove_gated_outliers() evaluates each gated residual
  // without its loss, and removes it if chi2 = |r|^2 > threshold or it cannot be evaluated
  // (a point behind the camera). Returns the number removed.
  void gate(ceres::ResidualBlockId id, double chi2_threshold);
  int remove_gated_outliers();

  int num_residuals() const;
  int num_free_poses() const;
  SolveSummary solve(const SolveOptions& options);

  ceres::Problem& problem() { return *problem_; }

 private:
  struct Block {
    double* data;
    int size;
    bool is_pose;
    bool fixed;
    bool eliminate;
  };
  int register_block(double* data, int size, bool is_pose, bool fixed, bool eliminate);
  // every add_* ends here: into Ceres' problem, or kept for the built-in solver
  ceres::ResidualBlockId add_block(ceres::CostFunction* cost, ceres::LossFunction* loss,
                                   const std::vector<int>& blocks);
  SolveSummary solve_builtin(const SolveOptions& options);
  double* allocate(int size);  // `size` doubles from the current buffer (a new one if full)

  struct Buffer {
    std::unique_ptr<double[]> data;
    int capacity = 0;
    int used = 0;
  };

  std::unique_ptr<ceres::Problem> problem_;
  std::unique_ptr<ceres::Manifold> pose_manifold_;
  std::vector<Buffer> storage_;  // parameter values; earlier buffers stay where they are
  std::vector<Block> blocks_;
  std::map<double, std::unique_ptr<ceres::LossFunction>> losses_;
  std::vector<std::pair<ceres::ResidualBlockId, double>> gated_;
  bool blocks_in_ceres_ = true;
  // the residuals kept for the built-in solver (keep_blocks_out_of_ceres), handed to it as
  // they are; the builder owns their cost functions
  std::vector<std::unique_ptr<ceres::CostFunction>> recorded_costs_;
  std::vector<BlockLMResidual> recorded_;
};

}  // namespace twistslam::optim::detail
