#pragma once
// Private (Eigen only): the trust-region rules of Ceres' Levenberg-Marquardt that the
// built-in solvers (schur_lm.hpp, block_lm.hpp) follow, so that they take Ceres' steps:
// the diagonal clamp, the radius after a taken / rejected / invalid step, and the pose
// manifold's Plus (pose_parameterization.hpp).
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

#include <limits>

#include "geometry/types.hpp"
#include "optim/schur_lm.hpp"

namespace twistslam::optim::detail {

// Ceres' defaults (Solver::Options, LevenbergMarquardtStrategy)
constexpr double kLMMinDiagonal = 1e-6;
constexpr double kLMMaxDiagonal = 1e32;
constexpr double kLMMaxRadius = 1e16;
constexpr double kLMMinRadius = 1e-32;
constexpr double kLMMinRelativeDecrease = 1e-3;
constexpr int kLMMaxConsecutiveInvalidSteps = 5;

// The damping added to a diagonal entry d of the scaled J^T J: clamp(d) / radius.
inline double lm_damping(double d, double radius) {
  return std::clamp(d, kLMMinDiagonal, kLMMaxDiagonal) / radius;
}

struct LMRadius {
  double radius;
  double decrease = 2.0;
  explicit LMRadius(double initial) : radius(initial) {}
  // a step whose cost decrease is rho times the model's
  void taken(double rho) {
    radius = std::min(kLMMaxRadius, radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)));
    decrease = 2.0;
  }
  // a rejected or invalid step: halved, then quartered, ...
  void shrink() {
    radius /= decrease;
    decrease *= 2.0;
  }
  bool too_small() const { return radius < kLMMinRadius; }
};

// A solve's start from the initial state's cost: its summary's initial cost and first
// iteration, or false (the summary says why) when that state cannot be evaluated
inline bool begin_solve(double initial_cost, SchurLMSummary* out) {
  if (!std::isfinite(initial_cost)) {
    out->message = "the initial state cannot be evaluated";
    return false;
  }
  out->initial_cost = initial_cost;
  out->iterations = 1;
  return true;
}

// One solve's step decisions, in Ceres' order: an invalid step (no model decrease) shrinks
// the region, five in a row fail the solve; a step too short for the parameter tolerance or
// changing the cost by less than the function tolerance ends it without being taken or
// counted; a step is taken when the cost fell by more than 1e-3 of the model's decrease.
class LMControl {
 public:
  enum class Verdict { kTake, kReject, kStop };

  LMControl(const SchurLMOptions& options, SchurLMSummary* summary)
      : options_(options), out_(*summary), region_(options.initial_trust_region_radius) {
    out_.message = "maximum number of iterations";
  }
  double radius() const { return region_.radius; }
  bool usable() const { return usable_; }

  // Before each step: false when the iterations are used up (counts the step otherwise).
  bool next_step() {
    if (steps_ >= options_.max_iterations) return false;
    ++steps_;
    ++out_.iterations;
    return true;
  }
  // A step without a model decrease (or a failed solve): true to stop the solve.
  bool invalid_step() {
    if (++invalid_in_a_row_ >= kLMMaxConsecutiveInvalidSteps) {
      usable_ = false;
      out_.message = "too many invalid steps in a row";
      return true;
    }
    region_.shrink();
    return region_.too_small();
  }
  // A valid step of length step_norm from x (norm x_norm): true to stop without taking it.
  bool step_too_short(double step_norm, double x_norm) {
    invalid_in_a_row_ = 0;
    if (step_norm > options_.parameter_tolerance * (x_norm + options_.parameter_tolerance)) return false;
    --out_.iterations;
    out_.message = "parameter tolerance reached";
    return true;
  }
  // The candidate's cost (+inf: it cannot be evaluated) against the current one.
  Verdict judge(double cost, double candidate_cost, double model_change) {
    if (std::isfinite(candidate_cost) &&
        std::abs(cost - candidate_cost) <= options_.function_tolerance * cost) {
      --out_.iterations;
      out_.message = "function tolerance reached";
      return Verdict::kStop;
    }
    const double rho = std::isfinite(candidate_cost) ? (cost - candidate_cost) / model_change
                                                     : -std::numeric_limits<double>::infinity();
    if (rho > kLMMinRelativeDecrease) {
      region_.taken(rho);
      return Verdict::kTake;
    }
    region_.shrink();
    if (!region_.too_small()) return Verdict::kReject;
    out_.message = "minimum trust region radius reached";
    return Verdict::kStop;
  }

 private:
  const SchurLMOptions& options_;
  SchurLMSummary& out_;
  LMRadius region_;
  int steps_ = 0, invalid_in_a_row_ = 0;
  bool usable_ = true;
};

// x (+) delta on R^3 x SO(3): t + v, [cos|w|, sin|w| w / |w|] * q
inline void pose_plus(const double* x, const double* delta, double* out) {
  for (int k = 0; k < 3; ++k) out[k] = x[k] + delta[k];
  const Eigen::Map<const Eigen::Quaterniond> q(x + 3);
  const Vec3 w(delta[3], delta[4], delta[5]);
  const double angle = w.norm();
  Eigen::Map<Eigen::Quaterniond> q_out(out + 3);
  if (angle == 0.0) {
    q_out = q;
    return;
  }
  const Vec3 axis = (std::sin(angle) / angle) * w;
  q_out = Eigen::Quaterniond(std::cos(angle), axis.x(), axis.y(), axis.z()) * q;
}

// d (x (+) delta) / d delta at delta = 0 (7 x 6)
inline Eigen::Matrix<double, 7, 6> pose_plus_jacobian(const double* x) {
  const double qx = x[3], qy = x[4], qz = x[5], qw = x[6];
  Eigen::Matrix<double, 7, 6> J = Eigen::Matrix<double, 7, 6>::Zero();
  J.topLeftCorner<3, 3>().setIdentity();
  J.bottomRightCorner<4, 3>() << qw, qz, -qy,
                                -qz, qw, qx,
                                 qy, -qx, qw,
                                -qx, -qy, -qz;
  return J;
}

}  // namespace twistslam::optim::detail
