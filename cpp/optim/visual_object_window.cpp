#include "optim/visual_object_window.hpp"

#include <algorithm>

#include "geometry/se3.hpp"
#include "optim/problem_builder.hpp"

namespace twistslam::optim {

namespace {

// frames up to which the reduced system is solved densely (the sliding window's 8 always):
// with the points eliminated, a 100-pose track took about as long either way (crowded s2:
// 170-340 ms dense, 180-240 ms sparse, measured); a longer track's band stays sparse
constexpr int kDenseSchurMaxFrames = 50;
// e_rest holds the translation only: a rotation sigma this large (rad/frame) leaves turning free
constexpr double kRestSigmaRotationRad = 1e3;

// e_const's rotation sigma at window row i (the triple i-1, i, i+1): see the options
double const_rotation_sigma(const VisualObjectWindow& w, int i, const VisualObjectWindowOptions& o) {
  if (!(o.const_rotation_reference_step_m > 0)) return o.const_sigma_rotation;
  const double step_m = 0.5 * (w.T_w_o[i + 1].topRightCorner<3, 1>() -
                               w.T_w_o[i - 1].topRightCorner<3, 1>()).norm();
  const double fraction = std::clamp(step_m / o.const_rotation_reference_step_m,
                                     o.const_rotation_min_fraction, 1.0);
  return o.const_sigma_rotation * fraction;
}

// e_det's sigma factor for the detection of window row i: its box centre's range from the
// camera of that frame over the reference range, at least 1 (see the options)
double detection_range_scale(const VisualObjectWindow& w, int i, const VisualObjectWindowOptions& o) {
  if (!(o.det_sigma_reference_range_m > 0)) return 1.0;
  const Vec3 centre_c = (w.T_c_w[i] * w.T_w_det[i]).topRightCorner<3, 1>();
  return std::max(1.0, centre_c.norm() / o.det_sigma_reference_range_m);
}

// The axis-free e_head's poses around window row i: a before and c after it, each chord the
// fewest frames long that reaches axis_free_heading_min_chord_m (one frame when it is 0), both
// moving at least axis_free_heading_min_step_m per frame on average; unusable at the window's
// ends, short of either, or where every pose of the triple is fixed
struct AxisFreeTriple {
  bool usable = false;
  int a = 0, c = 0;
  Vec3 before = Vec3::Zero(), after = Vec3::Zero();
};

AxisFreeTriple axis_free_triple(const VisualObjectWindow& w, int i, const VisualObjectWindowOptions& o) {
  const int n = static_cast<int>(w.T_w_o.size());
  const auto position = [&w](int k) -> Vec3 { return w.T_w_o[k].topRightCorner<3, 1>(); };
  const double chord = o.axis_free_heading_min_chord_m;
  AxisFreeTriple t;
  t.a = i - 1;
  while (t.a > 0 && (position(i) - position(t.a)).norm() < chord) --t.a;
  t.c = i + 1;
  while (t.c + 1 < n && (position(t.c) - position(i)).norm() < chord) ++t.c;
  if (t.c < w.num_fixed_frames) return t;
  t.before = position(i) - position(t.a);
  t.after = position(t.c) - position(i);
  t.usable = t.before.norm() >= std::max(chord, o.axis_free_heading_min_step_m * (i - t.a)) &&
             t.after.norm() >= std::max(chord, o.axis_free_heading_min_step_m * (t.c - i));
  return t;
}

}  // namespace

VisualObjectWindowSummary refine_visual_object_window(const geometry::StereoCamera& camera,
                                                      VisualObjectWindow& w, const Mat6& Pi,
                                                      const VisualObjectWindowOptions& o) {
  VisualObjectWindowSummary out;
  const int n = static_cast<int>(w.T_w_o.size());
  if (n < 2 || static_cast<int>(w.T_c_w.size()) != n || w.num_fixed_frames >= n) return out;
  // Solved in the world translated to the first object position (as optimize_object_window):
  // a world twist's v is the velocity of the point at the origin, so far from the origin
  // e_const's translation sigma would also weigh rotation by the distance. A translation
  // keeps the free and planar sub-spaces, so Pi is unchanged.
  const Vec3 c = w.T_w_o.front().topRightCorner<3, 1>();
  Mat4 S = Mat4::Identity();  // T_local_w
  S.topRightCorner<3, 1>() = -c;
  const Mat4 S_inv = geometry::se3_inverse(S);

  detail::ProblemBuilder b;
  const bool dense = n <= kDenseSchurMaxFrames;
  if (dense && o.builtin_solver) b.keep_blocks_out_of_ceres();  // solve(): block_lm.hpp
  b.reserve(7 * 2 * n + 3 * static_cast<int>(w.X_o.size()));
  std::vector<int> camera_block(n), object_block(n), point_block(w.X_o.size(), -1);
  for (int i = 0; i < n; ++i) {
    camera_block[i] = b.add_pose(w.T_c_w[i] * S_inv, /*fixed=*/true);
    object_block[i] = b.add_pose(S * w.T_w_o[i], /*fixed=*/i < w.num_fixed_frames || i == w.gauge_frame);
  }
  std::vector<int> seen(w.X_o.size(), 0);
  for (const auto& obs : w.observations) ++seen[obs.point];
  for (size_t p = 0; p < w.X_o.size(); ++p)
    if (seen[p] > 0) point_block[p] = b.add_point(w.X_o[p], !o.refine_points);
  // e_dyna (eq. 9); Huber thresholds in sigmas, so they scale with them
  const double sigma_scale = o.reprojection_sigma_scale > 0 ? o.reprojection_sigma_scale : 1.0;
  for (const auto& obs : w.observations) {
    const double huber = obs.u_right >= 0 ? o.huber_stereo : o.huber_mono;
    b.add_dynamic_reprojection(camera_block[obs.frame], object_block[obs.frame],
                               point_block[obs.point], camera, obs.uv, obs.u_right,
                               obs.inv_sigma2 / (sigma_scale * sigma_scale), huber, o.min_depth);
  }
  const bool use_heading = o.use_heading && w.travel_axis_o.norm() > 0.5;  // a unit axis or zero
  const bool axis_free = o.use_heading && !use_heading && w.wheeled &&
                         o.axis_free_heading_min_step_m > 0 && w.up_w.norm() > 0.5;
  for (int i = 0; i + 1 < n; ++i) {
    const bool both_fixed = i + 1 < w.num_fixed_frames;
    if (o.use_link && !both_fixed)
      b.add_link(object_block[i], object_block[i + 1], Pi, o.link_sigma_translation,
                 o.link_sigma_rotation);
    if (use_heading && !both_fixed)
      b.add_heading(object_block[i], object_block[i + 1], w.travel_axis_o, w.up_w,
                    w.T_w_o[i + 1].topRightCorner<3, 1>() - w.T_w_o[i].topRightCorner<3, 1>(),
                    o.lateral_sigma, o.huber_heading);
    if (axis_free && i >= 1) {
      const AxisFreeTriple t = axis_free_triple(w, i, o);
      if (t.usable)
        b.add_axis_free_heading(object_block[t.a], object_block[i], object_block[t.c], w.up_w,
                                t.before, t.after, o.lateral_sigma, o.huber_heading);
    }
    if (o.rest_sigma_translation > 0 && !both_fixed)  // e_rest: a zero twist, translation only
      b.add_detection_twist(object_block[i], object_block[i + 1], Pi, Vec6::Zero(),
                            o.rest_sigma_translation, kRestSigmaRotationRad, 0.0);
    if (o.use_const && i >= 1 && i + 1 >= w.num_fixed_frames)
      b.add_constant_velocity(object_block[i - 1], object_block[i], object_block[i + 1], Pi,
                              o.const_sigma_translation, const_rotation_sigma(w, i, o),
                              o.huber_const);
  }
  // LiDAR terms, in the local frame: a world twist seen from S is Ad_S xi, so the measured
  // poses and motions are moved by S as the blocks are
  const bool with_det = static_cast<int>(w.T_w_det.size()) == n &&
                        static_cast<int>(w.has_detection.size()) == n;
  if (with_det) {
    for (int i = 0; i < n; ++i) {
      if (!w.has_detection[i]) continue;
      const Mat4 T_det = S * w.T_w_det[i];
      const double scale = detection_range_scale(w, i, o);
      if (o.use_detection_pose && i >= w.num_fixed_frames)
        b.add_detection_pose(object_block[i], T_det, scale * o.det_pose_sigma_translation,
                             scale * o.det_pose_sigma_rotation, o.huber_det);
      if (o.use_detection_twist && i + 1 < n && w.has_detection[i + 1] && i + 1 >= w.num_fixed_frames) {
        // the twist of two boxes is as uncertain as the farther of them
        const double twist_scale = std::max(scale, detection_range_scale(w, i + 1, o));
        b.add_detection_twist(object_block[i], object_block[i + 1], Pi,
                              geometry::twist_between(T_det, S * w.T_w_det[i + 1]),
                              twist_scale * o.det_sigma_translation,
                              twist_scale * o.det_sigma_rotation, o.huber_det);
      }
    }
  }
  if (o.use_registration && static_cast<int>(w.M_w_reg.size()) == n &&
      static_cast<int>(w.has_registration.size()) == n) {
    for (int i = 0; i + 1 < n; ++i) {
      if (!w.has_registration[i] || i + 1 < w.num_fixed_frames) continue;
      const Vec6 xi_r = geometry::se3_log(S * w.M_w_reg[i] * S_inv);  // eq. 7
      if (static_cast<int>(w.reg_covariance.size()) == n && w.reg_covariance[i].trace() > 0) {
        // eps moves M_w on the left: seen from S it is Ad_S eps, and log(exp(eps') exp(xi_r))
        // = xi_r + J_l^-1(xi_r) eps' to first order
        const Mat6 J = geometry::se3_left_jacobian_inverse(xi_r) * geometry::se3_adjoint(S);
        b.add_twist_measurement(object_block[i], object_block[i + 1], xi_r,
                                J * w.reg_covariance[i] * J.transpose(), o.huber_reg);
        continue;
      }
      const bool own_sigma = static_cast<int>(w.reg_sigma.size()) == n && w.reg_sigma[i].minCoeff() > 0;
      b.add_detection_twist(object_block[i], object_block[i + 1], Pi, xi_r,
                            own_sigma ? w.reg_sigma[i].x() : o.reg_sigma_translation,
                            own_sigma ? w.reg_sigma[i].y() : o.reg_sigma_rotation, o.huber_reg);
    }
  }
  out.num_residuals = b.num_residuals();
  if (out.num_residuals == 0) return out;
  detail::SolveOptions so;
  so.max_iterations = o.max_iterations;
  so.num_threads = 1;  // one thread: bit-for-bit reproducible (Ceres sums in scheduling order)
  // points eliminated; the reduced system of a sliding window's few poses is dense, a whole
  // track's (the final smoothing) is banded by e_const and the points' short lives
  so.linear_solver_override = dense ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
  so.initial_trust_region_radius = 1e4;
  so.function_tolerance = o.function_tolerance;
  const detail::SolveSummary s = b.solve(so);
  out.usable = s.usable;
  out.iterations = s.iterations;
  out.initial_cost = s.initial_cost;
  out.final_cost = s.final_cost;
  if (!out.usable) return out;
  for (int i = w.num_fixed_frames; i < n; ++i)
    if (i != w.gauge_frame) w.T_w_o[i] = S_inv * b.pose(object_block[i]);
  if (o.refine_points)
    for (size_t p = 0; p < w.X_o.size(); ++p)
      if (point_block[p] >= 0) w.X_o[p] = b.point(point_block[p]);
  return out;
}

}  // namespace twistslam::optim
