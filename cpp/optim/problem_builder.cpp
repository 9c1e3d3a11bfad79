#include "optim/problem_builder.hpp"

#include <ceres/ordered_groups.h>

#include <algorithm>
#include <stdexcept>

#include "optim/block_lm.hpp"
#include "optim/dynamic_reprojection_cost.hpp"
#include "optim/heading_cost.hpp"
#include "optim/object_costs.hpp"
#include "optim/pose_parameterization.hpp"
#include "optim/reprojection_costs.hpp"

namespace twistslam::optim::detail {

namespace {
// doubles of the first buffer when reserve() was not called: a window of a few object poses
// and twists fits; a bundle adjustment reserves its exact size
constexpr int kMinBufferDoubles = 256;

ceres::Problem::Options problem_options() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // shared, owned by the builder
  o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;       // idem
  o.enable_fast_removal = true;                              // outlier removal between passes
  return o;
}
}  // namespace

ProblemBuilder::ProblemBuilder()
    : problem_(std::make_unique<ceres::Problem>(problem_options())),
      pose_manifold_(std::make_unique<PoseManifold>()) {}

ProblemBuilder::~ProblemBuilder() {
  problem_.reset();  // before the losses, the manifold and the parameter storage it points to
}

int ProblemBuilder::register_block(double* data, int size, bool is_pose, bool fixed,
                                   bool eliminate) {
  if (blocks_in_ceres_) {
    if (is_pose) {
      problem_->AddParameterBlock(data, size, pose_manifold_.get());
    } else {
      problem_->AddParameterBlock(data, size);
    }
    if (fixed) problem_->SetParameterBlockConstant(data);
  }
  blocks_.push_back({data, size, is_pose, fixed, eliminate});
  return static_cast<int>(blocks_.size()) - 1;
}

void ProblemBuilder::reserve(int num_doubles) {
  if (num_doubles <= 0) return;
  if (!storage_.empty() && storage_.back().capacity - storage_.back().used >= num_doubles) return;
  storage_.push_back({std::make_unique<double[]>(num_doubles), num_doubles, 0});
}

double* ProblemBuilder::allocate(int size) {
  if (storage_.empty() || storage_.back().capacity - storage_.back().used < size) {
    // grow geometrically: a builder used without reserve() stays at a few buffers
    const int previous = storage_.empty() ? 0 : storage_.back().capacity;
    reserve(std::max({size, kMinBufferDoubles, 2 * previous}));
  }
  Buffer& buffer = storage_.back();
  double* data = buffer.data.get() + buffer.used;
  buffer.used += size;
  return data;
}

int ProblemBuilder::add_pose(const Mat4& T, bool fixed) {
  double* data = allocate(kPoseSize);
  pose_to_params(T, data);
  return register_block(data, kPoseSize, true, fixed, false);
}

int ProblemBuilder::add_point(const Vec3& X, bool fixed) {
  double* data = allocate(3);
  std::copy(X.data(), X.data() + 3, data);
  return register_block(data, 3, false, fixed, true);
}

int ProblemBuilder::add_vector(const double* values, int size, bool fixed, bool eliminate) {
  if (size <= 0) throw std::invalid_argument("ProblemBuilder::add_vector: size must be > 0");
  double* data = allocate(size);
  std::copy(values, values + size, data);
  return register_block(data, size, false, fixed, eliminate);
}

Mat4 ProblemBuilder::pose(int block) const { return params_to_pose(blocks_[block].data); }

Vec3 ProblemBuilder::point(int block) const {
  return Eigen::Map<const Vec3>(blocks_[block].data);
}

ceres::LossFunction* ProblemBuilder::huber(double delta) {
  if (!(delta > 0)) return nullptr;
  auto& loss = losses_[delta];
  if (!loss) loss = std::make_unique<ceres::HuberLoss>(delta);
  return loss.get();
}

ceres::ResidualBlockId ProblemBuilder::add_stereo_reprojection(
    int pose, int point, const geometry::StereoCamera& cam, const Vec2& uv, double u_right,
    double inv_sigma2, double huber_delta, double min_depth) {
  ceres::CostFunction* cost;
  if (u_right >= 0) {
    cost = new StereoReprojectionCost(&cam, Vec3(uv.x(), uv.y(), u_right), inv_sigma2,
                                      min_depth);
  } else {
    cost = new MonoReprojectionCost(&cam, uv, inv_sigma2, min_depth);
  }
  return add_block(cost, huber(huber_delta), {pose, point});
}

ceres::ResidualBlockId ProblemBuilder::add_constant_velocity(int pose_a, int pose_b, int pose_c,
                                                             const Mat6& Pi, double sigma_t,
                                                             double sigma_r, double huber_delta) {
  return add_block(make_constant_velocity_cost(Pi, sigma_t, sigma_r), huber(huber_delta),
                   {pose_a, pose_b, pose_c});
}

ceres::ResidualBlockId ProblemBuilder::add_detection_twist(int pose_a, int pose_b, const Mat6& Pi,
                                                           const Vec6& xi_d, double sigma_t,
                                                           double sigma_r, double huber_delta,
                                                           double information_scale) {
  return add_block(make_detection_twist_cost(Pi, xi_d, sigma_t, sigma_r, information_scale),
                   huber(huber_delta), {pose_a, pose_b});
}

ceres::ResidualBlockId ProblemBuilder::add_twist_measurement(int pose_a, int pose_b,
                                                             const Vec6& xi_m,
                                                             const Mat6& covariance,
                                                             double huber_delta) {
  return add_block(make_twist_measurement_cost(covariance, xi_m), huber(huber_delta),
                   {pose_a, pose_b});
}

ceres::ResidualBlockId ProblemBuilder::add_detection_pose(int pose, const Mat4& T_det,
                                                          double sigma_t, double sigma_r,
                                                          double huber_delta,
                                                          double information_scale) {
  return add_block(make_detection_pose_cost(T_det, sigma_t, sigma_r, information_scale),
                   huber(huber_delta), {pose});
}

ceres::ResidualBlockId ProblemBuilder::add_link(int pose_a, int pose_b, const Mat6& Pi,
                                                double sigma_t, double sigma_r) {
  return add_block(make_link_cost(Pi, sigma_t, sigma_r), nullptr, {pose_a, pose_b});
}

ceres::ResidualBlockId ProblemBuilder::add_heading(int pose_a, int pose_b, const Vec3& axis_o,
                                                   const Vec3& up_w, const Vec3& d_w,
                                                   double sigma_m, double huber_delta) {
  return add_block(make_heading_cost(axis_o, up_w, d_w, sigma_m), huber(huber_delta),
                   {pose_a, pose_b});
}

ceres::ResidualBlockId ProblemBuilder::add_axis_free_heading(int pose_a, int pose_b, int pose_c,
                                                             const Vec3& up_w, const Vec3& d1_w,
                                                             const Vec3& d2_w, double sigma_m,
                                                             double huber_delta) {
  return add_block(make_axis_free_heading_cost(up_w, d1_w, d2_w, sigma_m), huber(huber_delta),
                   {pose_a, pose_b, pose_c});
}

ceres::ResidualBlockId ProblemBuilder::add_dynamic_reprojection(
    int camera_pose, int object_pose, int object_point, const geometry::StereoCamera& cam,
    const Vec2& uv, double u_right, double inv_sigma2, double huber_delta, double min_depth) {
  return add_block(make_dynamic_reprojection_cost(&cam, uv, u_right, inv_sigma2, min_depth),
                   huber(huber_delta), {camera_pose, object_pose, object_point});
}

ceres::ResidualBlockId ProblemBuilder::add_residual(ceres::CostFunction* cost,
                                                    ceres::LossFunction* loss,
                                                    const std::vector<int>& blocks) {
  return add_block(cost, loss, blocks);
}

ceres::ResidualBlockId ProblemBuilder::add_block(ceres::CostFunction* cost, ceres::LossFunction* loss,
                                                 const std::vector<int>& blocks) {
  if (!blocks_in_ceres_) {  // kept for the built-in solver
    recorded_costs_.emplace_back(cost);
    recorded_.push_back({cost, loss, blocks});
    return nullptr;
  }
  std::vector<double*> ptrs;
  ptrs.reserve(blocks.size());
  for (int b : blocks) ptrs.push_back(blocks_[b].data);
  return problem_->AddResidualBlock(cost, loss, ptrs);
}

void ProblemBuilder::gate(ceres::ResidualBlockId id, double chi2_threshold) {
  if (!blocks_in_ceres_)
    throw std::logic_error("ProblemBuilder::gate: the built-in solver has no outlier gating");
  gated_.emplace_back(id, chi2_threshold);
}

int ProblemBuilder::remove_gated_outliers() {
  int removed = 0;
  std::vector<double> r;
  std::vector<std::pair<ceres::ResidualBlockId, double>> kept;
  kept.reserve(gated_.size());
  for (const auto& [id, threshold] : gated_) {
    r.resize(problem_->GetCostFunctionForResidualBlock(id)->num_residuals());
    double cost = 0;
    const bool ok = problem_->EvaluateResidualBlock(id, false, &cost, r.data(), nullptr);
    if (!ok || !std::isfinite(cost) || 2.0 * cost > threshold) {
      problem_->RemoveResidualBlock(id);
      ++removed;
    } else {
      kept.emplace_back(id, threshold);
    }
  }
  gated_.swap(kept);
  return removed;
}

int ProblemBuilder::num_residuals() const {
  return blocks_in_ceres_ ? problem_->NumResidualBlocks() : static_cast<int>(recorded_.size());
}

int ProblemBuilder::num_free_poses() const {
  return static_cast<int>(std::count_if(blocks_.begin(), blocks_.end(),
                                        [](const Block& b) { return b.is_pose && !b.fixed; }));
}

SolveSummary ProblemBuilder::solve(const SolveOptions& opt) {
  SolveSummary out;
  if (num_residuals() == 0) {
    out.message = "no residuals";
    return out;
  }
  if (!blocks_in_ceres_) return solve_builtin(opt);
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.max_num_iterations = std::max(opt.max_iterations, 0);
  o.num_threads = std::max(opt.num_threads, 1);
  o.function_tolerance = opt.function_tolerance;
  o.gradient_tolerance = opt.gradient_tolerance;
  o.parameter_tolerance = opt.parameter_tolerance;
  o.minimizer_progress_to_stdout = false;
  o.initial_trust_region_radius = opt.initial_trust_region_radius;
  o.logging_type = ceres::SILENT;
  switch (opt.linear_solver) {
    case BALinearSolver::kBuiltinDenseSchur:  // a problem it cannot take (object terms)
    case BALinearSolver::kDenseSchur: o.linear_solver_type = ceres::DENSE_SCHUR; break;
    case BALinearSolver::kSparseSchur: o.linear_solver_type = ceres::SPARSE_SCHUR; break;
    case BALinearSolver::kIterativeSchur:
      o.linear_solver_type = ceres::ITERATIVE_SCHUR;
      o.preconditioner_type = ceres::SCHUR_JACOBI;
      break;
    case BALinearSolver::kAuto:
      // The reduced camera system of a local window (~10-30 poses, 6 tangent dof each) is
      // small and dense: dense Cholesky beats sparse bookkeeping up to about a hundred poses.
      o.linear_solver_type = num_free_poses() <= 100 ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
      break;
  }
  if (o.linear_solver_type == ceres::SPARSE_SCHUR &&
      !ceres::IsSparseLinearAlgebraLibraryTypeAvailable(o.sparse_linear_algebra_library_type)) {
    o.linear_solver_type = ceres::ITERATIVE_SCHUR;
    o.preconditioner_type = ceres::SCHUR_JACOBI;
  }
  // Schur ordering: points (and other eliminated blocks) first, poses and the rest after.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (const Block& b : blocks_) ordering->AddElementToGroup(b.data, b.eliminate ? 0 : 1);
  o.linear_solver_ordering = ordering;
  if (opt.linear_solver_override) {
    o.linear_solver_type = *opt.linear_solver_override;
    // a Schur solver eliminates the points; without them (or without Schur) Ceres orders
    const bool schur = o.linear_solver_type == ceres::DENSE_SCHUR ||
                       o.linear_solver_type == ceres::SPARSE_SCHUR ||
                       o.linear_solver_type == ceres::ITERATIVE_SCHUR;
    const bool points = std::any_of(blocks_.begin(), blocks_.end(), [](const Block& b) { return b.eliminate; });
    if (!schur || !points) o.linear_solver_ordering.reset();
    if (o.linear_solver_type == ceres::ITERATIVE_SCHUR) o.preconditioner_type = ceres::SCHUR_JACOBI;
  }

  std::string error;
  if (!o.IsValid(&error)) {
    out.message = "invalid solver options: " + error;
    return out;
  }
  ceres::Solver::Summary summary;
  ceres::Solve(o, problem_.get(), &summary);
  out.usable = summary.IsSolutionUsable();
  out.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  out.initial_cost = summary.initial_cost;
  out.final_cost = summary.final_cost;
  out.message = summary.message;
  return out;
}

SchurLMOptions builtin_options(const SolveOptions& o) {
  SchurLMOptions lo;
  lo.max_iterations = std::max(o.max_iterations, 0);
  lo.function_tolerance = o.function_tolerance;
  lo.gradient_tolerance = o.gradient_tolerance;
  lo.parameter_tolerance = o.parameter_tolerance;
  lo.initial_trust_region_radius = o.initial_trust_region_radius;
  return lo;
}

SolveSummary ProblemBuilder::solve_builtin(const SolveOptions& opt) {
  std::vector<BlockLMBlock> blocks;
  blocks.reserve(blocks_.size());
  for (const Block& b : blocks_) blocks.push_back({b.data, b.size, b.is_pose, b.fixed, b.eliminate});
  return solve_block_lm(blocks, recorded_, builtin_options(opt));
}

}  // namespace twistslam::optim::detail
