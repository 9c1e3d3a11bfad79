// Local bundle adjustment: builds the Ceres problem of paper eq. 9 through ProblemBuilder
// (e_stat here; e_dyna and e_link of the problem's objects in ba_dynamic_terms.cpp), solves it in two passes with the outliers of the
// first pass removed (ORB-SLAM's local BA scheme), writes the result back.
#include "optim/bundle_adjustment.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "geometry/se3.hpp"
#include "optim/ba_terms.hpp"
#include "optim/pose_parameterization.hpp"
#include "optim/schur_lm.hpp"

namespace twistslam::optim {

namespace {

using detail::DynamicReprojectionTerms;
using detail::huber_rho;
using detail::ObservationError;
using detail::ProblemBuilder;

ObservationError observation_error(const geometry::StereoCamera& cam, const Mat4& T_c_w,
                                   const Vec3& X_w, const BAObservation& o, double min_depth) {
  return detail::observation_error(cam, T_c_w, X_w, o.uv, o.u_right, o.inv_sigma2, min_depth);
}

bool valid_camera(const geometry::StereoCamera& cam) {
  return std::isfinite(cam.fx) && std::isfinite(cam.fy) && cam.fx > 0 && cam.fy > 0 &&
         std::isfinite(cam.cx) && std::isfinite(cam.cy) && cam.t_left.allFinite() &&
         cam.t_right.allFinite();
}

void check_indices(const BAProblem& p) {
  const int K = static_cast<int>(p.keyframes.size());
  const int M = static_cast<int>(p.points.size());
  for (size_t e = 0; e < p.observations.size(); ++e) {
    const BAObservation& o = p.observations[e];
    if (o.keyframe < 0 || o.keyframe >= K) {
      throw std::invalid_argument("bundle_adjust: observation " + std::to_string(e) +
                                  " has keyframe index " + std::to_string(o.keyframe) +
                                  " outside [0, " + std::to_string(K) + ")");
    }
    if (o.point < 0 || o.point >= M) {
      throw std::invalid_argument("bundle_adjust: observation " + std::to_string(e) +
                                  " has point index " + std::to_string(o.point) + " outside [0, " +
                                  std::to_string(M) + ")");
    }
  }
}

// e_stat of eq. 9: one reprojection residual per valid observation of a static point.
// The object families of later issues get a struct like this one (their own blocks, their
// own residuals, their own statistics) added to the same ProblemBuilder in bundle_adjust().
class StaticReprojectionTerms {
 public:
  StaticReprojectionTerms(const BAProblem& problem, const geometry::StereoCamera& cam,
                          const BundleAdjustmentOptions& opt)
      : p_(problem), cam_(cam), opt_(opt), used_(problem.observations.size(), 0) {}

  // Adds the blocks and residuals; an observation is used if all its data is finite and the
  // point is in front of the camera at the initial state. A keyframe gets its block with its
  // first used observation (the dynamic terms use these blocks, and skip keyframes without).
  // With `lm`, the observations go to that solver (on the builder's blocks) instead of Ceres.
  void add_to(ProblemBuilder& b, detail::SchurLM* lm = nullptr) {
    kf_block_.assign(p_.keyframes.size(), -1);
    pt_block_.assign(p_.points.size(), -1);
    std::vector<int> lm_pose(lm ? p_.keyframes.size() : 0, -1), lm_point(lm ? p_.points.size() : 0, -1);
    std::vector<std::uint8_t> kf_ok(p_.keyframes.size()), pt_ok(p_.points.size());
    for (size_t k = 0; k < p_.keyframes.size(); ++k) {
      const Mat4& T = p_.keyframes[k].T_c_w;
      kf_ok[k] = T.allFinite() && geometry::is_rigid_transform(T, 1e-3);
    }
    for (size_t j = 0; j < p_.points.size(); ++j) pt_ok[j] = p_.points[j].X_w.allFinite();

    for (size_t e = 0; e < p_.observations.size(); ++e) {
      const BAObservation& o = p_.observations[e];
      if (!kf_ok[o.keyframe] || !pt_ok[o.point] || !o.uv.allFinite() ||
          !std::isfinite(o.u_right) || !std::isfinite(o.inv_sigma2) || !(o.inv_sigma2 > 0)) {
        continue;
      }
      const ObservationError err = error(e, p_.keyframes[o.keyframe].T_c_w, p_.points[o.point].X_w);
      if (!err.in_front) continue;
      if (kf_block_[o.keyframe] < 0) {
        const bool fixed = p_.keyframes[o.keyframe].fixed;
        kf_block_[o.keyframe] = b.add_pose(p_.keyframes[o.keyframe].T_c_w, fixed);
        if (lm) lm_pose[o.keyframe] = lm->add_pose(b.data(kf_block_[o.keyframe]), fixed);
      }
      if (pt_block_[o.point] < 0) {
        const bool fixed = p_.points[o.point].fixed;
        pt_block_[o.point] = b.add_point(p_.points[o.point].X_w, fixed);
        if (lm) lm_point[o.point] = lm->add_point(b.data(pt_block_[o.point]), fixed);
      }
      const bool stereo = o.u_right >= 0;
      used_[e] = 1;
      ++num_used_;
      if (lm) {
        detail::SchurLMObservation obs;
        obs.pose = lm_pose[o.keyframe];
        obs.point = lm_point[o.point];
        obs.z = Vec3(o.uv.x(), o.uv.y(), stereo ? o.u_right : -1.0);
        obs.sqrt_info = std::sqrt(o.inv_sigma2);
        obs.huber_delta = stereo ? opt_.huber_delta_stereo : opt_.huber_delta_mono;
        obs.chi2_gate = opt_.remove_outliers ? threshold(o) : 0.0;
        lm->add_observation(obs);
        continue;
      }
      const auto id = b.add_stereo_reprojection(
          kf_block_[o.keyframe], pt_block_[o.point], cam_, o.uv, o.u_right, o.inv_sigma2,
          stereo ? opt_.huber_delta_stereo : opt_.huber_delta_mono, opt_.min_depth);
      if (opt_.remove_outliers) b.gate(id, threshold(o));
    }
  }

  int num_used() const { return num_used_; }
  const std::vector<int>& keyframe_blocks() const { return kf_block_; }

  // Per observation error at the builder's current state (for used observations).
  std::vector<ObservationError> errors(const ProblemBuilder& b) const {
    std::vector<ObservationError> out(p_.observations.size());
    std::vector<Mat4> T(p_.keyframes.size());
    for (size_t k = 0; k < T.size(); ++k)
      if (kf_block_[k] >= 0) T[k] = b.pose(kf_block_[k]);
    for (size_t e = 0; e < out.size(); ++e) {
      if (!used_[e]) continue;
      const BAObservation& o = p_.observations[e];
      out[e] = error(e, T[o.keyframe], b.point(pt_block_[o.point]));
    }
    return out;
  }

  // 0.5 * sum of Huber(chi2) over the used observations (a point behind the camera costs as
  // much as a gross outlier).
  double cost(const std::vector<ObservationError>& errs) const {
    double c = 0;
    for (size_t e = 0; e < errs.size(); ++e) {
      if (!used_[e]) continue;
      const double d = p_.observations[e].u_right >= 0 ? opt_.huber_delta_stereo
                                                       : opt_.huber_delta_mono;
      c += 0.5 * huber_rho(errs[e].in_front ? errs[e].chi2 : 1e4 * d * d, d);
    }
    return c;
  }

  bool is_outlier(size_t e, const ObservationError& err) const {
    return !used_[e] || !err.in_front || err.chi2 > threshold(p_.observations[e]);
  }

  void write_back(const ProblemBuilder& b, BAProblem& problem) const {
    for (size_t k = 0; k < kf_block_.size(); ++k) {
      if (kf_block_[k] >= 0 && !problem.keyframes[k].fixed) {
        problem.keyframes[k].T_c_w = b.pose(kf_block_[k]);
      }
    }
    for (size_t j = 0; j < pt_block_.size(); ++j) {
      if (pt_block_[j] >= 0 && !problem.points[j].fixed) problem.points[j].X_w = b.point(pt_block_[j]);
    }
  }

 private:
  ObservationError error(size_t e, const Mat4& T, const Vec3& X) const {
    return observation_error(cam_, T, X, p_.observations[e], opt_.min_depth);
  }
  double threshold(const BAObservation& o) const {
    return o.u_right >= 0 ? opt_.chi2_stereo : opt_.chi2_mono;
  }

  const BAProblem& p_;
  const geometry::StereoCamera& cam_;
  const BundleAdjustmentOptions& opt_;
  std::vector<int> kf_block_, pt_block_;
  std::vector<std::uint8_t> used_;
  int num_used_ = 0;
};

// Snapshot of every parameter block, to undo a failed pass.
std::vector<std::vector<double>> snapshot(ProblemBuilder& b) {
  std::vector<std::vector<double>> s(b.num_blocks());
  for (int i = 0; i < b.num_blocks(); ++i) s[i].assign(b.data(i), b.data(i) + b.size(i));
  return s;
}

void restore(ProblemBuilder& b, const std::vector<std::vector<double>>& s) {
  for (int i = 0; i < b.num_blocks(); ++i) std::copy(s[i].begin(), s[i].end(), b.data(i));
}

int num_free_keyframes(const BAProblem& p) {
  return static_cast<int>(std::count_if(p.keyframes.begin(), p.keyframes.end(),
                                        [](const BAKeyframe& k) { return !k.fixed; }));
}

}  // namespace

BundleAdjustmentReport bundle_adjust(BAProblem& problem, const geometry::StereoCamera& cam,
                                     const BundleAdjustmentOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed_ms = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
        .count();
  };
  check_indices(problem);
  detail::check_dynamic_indices(problem);

  BundleAdjustmentReport report;
  const size_t E = problem.observations.size();
  report.outlier.assign(E, 1);
  report.num_outliers = static_cast<int>(E);
  report.dynamic_outlier.assign(problem.dynamic_observations.size(), 1);
  if (!valid_camera(cam)) {
    report.message = "invalid camera";
    report.solve_ms = elapsed_ms();
    return report;
  }

  ProblemBuilder builder;
  {  // every block in one buffer, in the order added: bit-identical results (reserve())
    size_t doubles = detail::kPoseSize * problem.keyframes.size() + 3 * problem.points.size();
    for (const BAObject& o : problem.objects)
      doubles += detail::kPoseSize * o.poses.size() + 3 * o.points_o.size();
    builder.reserve(static_cast<int>(doubles));
  }
  // a static problem (no object terms) goes to the built-in dense-Schur LM (schur_lm.hpp)
  std::unique_ptr<detail::SchurLM> lm;
  if (problem.objects.empty() && problem.dynamic_observations.empty() &&
      (opt.linear_solver == BALinearSolver::kBuiltinDenseSchur ||
       (opt.linear_solver == BALinearSolver::kAuto && num_free_keyframes(problem) <= 100))) {
    builder.keep_blocks_out_of_ceres();
    lm = std::make_unique<detail::SchurLM>(cam, opt.min_depth);
  }
  StaticReprojectionTerms stat(problem, cam, opt);
  stat.add_to(builder, lm.get());
  DynamicReprojectionTerms dyna(problem, cam, opt);
  dyna.add_to(builder, stat.keyframe_blocks());
  report.num_residuals = stat.num_used();
  report.num_dynamic_residuals = dyna.num_used();
  report.num_object_motions = dyna.num_motions();
  report.num_object_boxes = dyna.num_boxes();
  report.num_object_const = dyna.num_const();
  if ((lm ? lm->num_observations() : builder.num_residuals()) == 0) {
    report.message = "no valid observations";
    report.solve_ms = elapsed_ms();
    return report;
  }
  const std::vector<ObservationError> initial = stat.errors(builder);
  report.initial_cost = stat.cost(initial);

  detail::SolveOptions so;
  so.num_threads = opt.num_threads;
  so.linear_solver = opt.linear_solver;
  so.function_tolerance = opt.function_tolerance;
  so.initial_trust_region_radius = opt.initial_trust_region_radius;
  so.max_iterations = opt.remove_outliers ? opt.max_iterations_first
                                          : opt.max_iterations_first + opt.max_iterations_second;
  const auto solve = [&]() -> detail::SolveSummary {
    return lm ? lm->solve(detail::builtin_options(so)) : builder.solve(so);
  };
  const detail::SolveSummary first = solve();
  report.iterations = first.iterations;
  report.message = first.message;
  if (!first.usable) {
    report.solve_ms = elapsed_ms();
    return report;  // nothing written back
  }
  if (opt.remove_outliers && opt.max_iterations_second > 0) {
    if (lm) lm->remove_gated_outliers();
    else builder.remove_gated_outliers();
    if ((lm ? lm->num_observations() : builder.num_residuals()) > 0) {
      const auto before = snapshot(builder);
      so.max_iterations = opt.max_iterations_second;
      const detail::SolveSummary second = solve();
      report.iterations += second.iterations;
      report.message = second.message;
      if (!second.usable) restore(builder, before);  // keep the first pass' solution
    }
  }
  stat.write_back(builder, problem);
  dyna.write_back(builder, problem);
  report.dynamic_outlier = dyna.outliers(builder);

  const std::vector<ObservationError> final_errors = stat.errors(builder);
  report.final_cost = stat.cost(final_errors);
  double sq0 = 0, sq1 = 0;
  int dims = 0;
  report.num_outliers = 0;
  for (size_t e = 0; e < E; ++e) {
    report.outlier[e] = stat.is_outlier(e, final_errors[e]);
    report.num_outliers += report.outlier[e];
    if (!report.outlier[e]) {
      sq0 += initial[e].sq_px;
      sq1 += final_errors[e].sq_px;
      dims += final_errors[e].dims;
    }
  }
  if (dims > 0) {
    report.initial_rmse_px = std::sqrt(sq0 / dims);
    report.final_rmse_px = std::sqrt(sq1 / dims);
  }
  report.converged = true;
  report.solve_ms = elapsed_ms();
  return report;
}

}  // namespace twistslam::optim
