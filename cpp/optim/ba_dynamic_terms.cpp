// e_dyna and e_link of the local BA (paper eq. 9, ba_terms.hpp): moving objects' keypoints
// reprojected through their pose at each keyframe, consecutive poses tied by the link; and
// the terms between those poses: e_const, and the LiDAR terms (e_det / e_reg, the box prior)
// relative to the cameras.
#include <stdexcept>
#include <string>

#include "geometry/se3.hpp"
#include "optim/ba_terms.hpp"
#include "optim/ba_object_costs.hpp"

namespace twistslam::optim::detail {

namespace {

Vec3 to_world(const Mat4& T_w_o, const Vec3& X_o) {
  return T_w_o.topLeftCorner<3, 3>() * X_o + T_w_o.topRightCorner<3, 1>();
}

}  // namespace

void check_dynamic_indices(const BAProblem& p) {
  const int K = static_cast<int>(p.keyframes.size());
  const int O = static_cast<int>(p.objects.size());
  auto fail = [](const std::string& what, size_t e, const std::string& field, int value, int n) {
    throw std::invalid_argument("bundle_adjust: " + what + " " + std::to_string(e) + " has " +
                                field + " " + std::to_string(value) + " outside [0, " +
                                std::to_string(n) + ")");
  };
  for (size_t o = 0; o < p.objects.size(); ++o)
    for (const BAObjectPose& pose : p.objects[o].poses)
      if (pose.keyframe < 0 || pose.keyframe >= K) fail("object", o, "pose keyframe", pose.keyframe, K);
  for (size_t o = 0; o < p.objects.size(); ++o) {
    const int P = static_cast<int>(p.objects[o].poses.size());
    for (const BAObjectMotion& m : p.objects[o].motions) {
      if (m.pose_a < 0 || m.pose_a >= P) fail("object", o, "motion pose_a", m.pose_a, P);
      if (m.pose_b < 0 || m.pose_b >= P) fail("object", o, "motion pose_b", m.pose_b, P);
    }
    for (const BAObjectBox& box : p.objects[o].boxes)
      if (box.pose < 0 || box.pose >= P) fail("object", o, "box pose", box.pose, P);
  }
  for (size_t e = 0; e < p.dynamic_observations.size(); ++e) {
    const BADynamicObservation& d = p.dynamic_observations[e];
    if (d.object < 0 || d.object >= O) fail("dynamic observation", e, "object index", d.object, O);
    const BAObject& obj = p.objects[d.object];
    const int P = static_cast<int>(obj.poses.size()), M = static_cast<int>(obj.points_o.size());
    if (d.pose < 0 || d.pose >= P) fail("dynamic observation", e, "pose index", d.pose, P);
    if (d.point < 0 || d.point >= M) fail("dynamic observation", e, "point index", d.point, M);
  }
}

bool DynamicReprojectionTerms::usable(const BADynamicObservation& o) const {
  const BAObject& obj = p_.objects[o.object];
  const BAObjectPose& pose = obj.poses[o.pose];
  if (keyframe_blocks_[pose.keyframe] < 0 || !obj.Pi.allFinite() || !pose.T_w_o.allFinite() ||
      !geometry::is_rigid_transform(pose.T_w_o, 1e-3) || !obj.points_o[o.point].allFinite() ||
      !o.uv.allFinite() || !std::isfinite(o.u_right) || !std::isfinite(o.inv_sigma2) ||
      !(o.inv_sigma2 > 0))
    return false;
  const Mat4& T_c_w = p_.keyframes[pose.keyframe].T_c_w;
  return observation_error(cam_, T_c_w, to_world(pose.T_w_o, obj.points_o[o.point]), o.uv,
                           o.u_right, o.inv_sigma2, opt_.min_depth)
      .in_front;
}

void DynamicReprojectionTerms::add_to(ProblemBuilder& b, const std::vector<int>& keyframe_blocks) {
  keyframe_blocks_ = keyframe_blocks;
  const size_t E = p_.dynamic_observations.size();
  used_.assign(E, 0);
  pose_block_.assign(p_.objects.size(), {});
  point_block_.assign(p_.objects.size(), {});
  // usable observations, and how often each point is seen through them
  std::vector<std::uint8_t> ok(E, 0);
  std::vector<std::vector<int>> seen(p_.objects.size());
  for (size_t o = 0; o < p_.objects.size(); ++o) seen[o].assign(p_.objects[o].points_o.size(), 0);
  for (size_t e = 0; e < E; ++e) {
    const BADynamicObservation& d = p_.dynamic_observations[e];
    ok[e] = usable(d);
    if (ok[e]) ++seen[d.object][d.point];
  }
  // poses observed through points seen twice; an object needs two of them
  std::vector<std::vector<std::uint8_t>> pose_used(p_.objects.size());
  for (size_t o = 0; o < p_.objects.size(); ++o) pose_used[o].assign(p_.objects[o].poses.size(), 0);
  for (size_t e = 0; e < E; ++e) {
    const BADynamicObservation& d = p_.dynamic_observations[e];
    if (ok[e] && seen[d.object][d.point] >= 2) pose_used[d.object][d.pose] = 1;
  }
  for (size_t o = 0; o < p_.objects.size(); ++o) {
    const BAObject& obj = p_.objects[o];
    int n = 0;
    for (auto u : pose_used[o]) n += u;
    pose_block_[o].assign(obj.poses.size(), -1);
    point_block_[o].assign(obj.points_o.size(), -1);
    if (n < 2) continue;
    int previous = -1;
    for (size_t k = 0; k < obj.poses.size(); ++k) {
      if (!pose_used[o][k]) continue;
      pose_block_[o][k] = b.add_pose(obj.poses[k].T_w_o, obj.poses[k].fixed);
      // e_link between consecutive poses of the object (the time order of poses)
      if (previous >= 0)
        b.add_link(previous, pose_block_[o][k], obj.Pi, opt_.link_sigma_translation,
                   opt_.link_sigma_rotation);
      previous = pose_block_[o][k];
    }
  }
  add_object_motion_terms(b);
  for (size_t e = 0; e < E; ++e) {
    const BADynamicObservation& d = p_.dynamic_observations[e];
    if (!ok[e] || seen[d.object][d.point] < 2 || pose_block_[d.object][d.pose] < 0) continue;
    int& point = point_block_[d.object][d.point];
    if (point < 0) point = b.add_point(p_.objects[d.object].points_o[d.point], false);
    const int kf = keyframe_blocks_[p_.objects[d.object].poses[d.pose].keyframe];
    const bool stereo = d.u_right >= 0;
    const auto id = b.add_dynamic_reprojection(
        kf, pose_block_[d.object][d.pose], point, cam_, d.uv, d.u_right, d.inv_sigma2,
        stereo ? opt_.huber_delta_stereo : opt_.huber_delta_mono, opt_.min_depth);
    if (opt_.remove_outliers) b.gate(id, threshold(d));
    used_[e] = 1;
    ++num_used_;
  }
}

namespace {

bool usable_sigmas(double sigma_t, double sigma_r) {
  return std::isfinite(sigma_t) && sigma_t > 0 && std::isfinite(sigma_r) && sigma_r > 0;
}

}  // namespace

void DynamicReprojectionTerms::add_object_motion_terms(ProblemBuilder& b) {
  for (size_t o = 0; o < p_.objects.size(); ++o) {
    const BAObject& obj = p_.objects[o];
    // e_const over the poses in the problem with known, increasing frames
    if (opt_.object_const && usable_sigmas(obj.const_sigma_translation, obj.const_sigma_rotation)) {
      std::vector<int> chain;  // pose indices
      for (size_t k = 0; k < obj.poses.size(); ++k)
        if (pose_block_[o][k] >= 0 && obj.poses[k].frame >= 0 &&
            (chain.empty() || obj.poses[k].frame > obj.poses[chain.back()].frame))
          chain.push_back(static_cast<int>(k));
      for (size_t j = 2; j < chain.size(); ++j) {
        const BAObjectPose &a = obj.poses[chain[j - 2]], &m = obj.poses[chain[j - 1]],
                           &c = obj.poses[chain[j]];
        const int n_ab = m.frame - a.frame, n_bc = c.frame - m.frame;
        const double scale = std::sqrt(0.5 * (n_ab + n_bc));
        b.add_residual(make_keyframe_constant_velocity_cost(
                           obj.Pi, n_ab, n_bc, m.T_w_o.topRightCorner<3, 1>(),
                           scale * obj.const_sigma_translation, scale * obj.const_sigma_rotation),
                       b.huber(obj.const_huber_delta),
                       {pose_block_[o][chain[j - 2]], pose_block_[o][chain[j - 1]], pose_block_[o][chain[j]]});
        ++num_const_;
      }
    }
    // only between poses e_dyna put in the problem: a pose held by LiDAR terms alone would
    // bring no camera information, and its keyframe might not be in the problem
    auto camera_block = [&](int pose) {
      return pose_block_[o][pose] >= 0 ? keyframe_blocks_[obj.poses[pose].keyframe] : -1;
    };
    for (const BAObjectMotion& m : obj.motions) {
      const int cam_a = camera_block(m.pose_a), cam_b = camera_block(m.pose_b);
      if (cam_a < 0 || cam_b < 0 || cam_a == cam_b || !m.D.allFinite() ||
          !geometry::is_rigid_transform(m.D, 1e-3) || !usable_sigmas(m.sigma_translation, m.sigma_rotation))
        continue;
      const Vec3 c = obj.poses[m.pose_a].T_w_o.topRightCorner<3, 1>();
      b.add_residual(make_camera_relative_motion_cost(obj.Pi, m.D, c, m.sigma_translation, m.sigma_rotation),
                     b.huber(m.huber_delta),
                     {cam_a, cam_b, pose_block_[o][m.pose_a], pose_block_[o][m.pose_b]});
      ++num_motions_;
    }
    for (const BAObjectBox& box : obj.boxes) {
      const int cam = camera_block(box.pose);
      if (cam < 0 || !box.T_c_box.allFinite() || !geometry::is_rigid_transform(box.T_c_box, 1e-3) ||
          !usable_sigmas(box.sigma_translation, box.sigma_rotation))
        continue;
      b.add_residual(make_camera_relative_box_cost(box.T_c_box, box.sigma_translation, box.sigma_rotation),
                     b.huber(box.huber_delta), {cam, pose_block_[o][box.pose]});
      ++num_boxes_;
    }
  }
}

std::vector<std::uint8_t> DynamicReprojectionTerms::outliers(const ProblemBuilder& b) const {
  std::vector<std::uint8_t> out(p_.dynamic_observations.size(), 1);
  for (size_t e = 0; e < out.size(); ++e) {
    if (!used_[e]) continue;
    const BADynamicObservation& d = p_.dynamic_observations[e];
    const Mat4 T_c_w = b.pose(keyframe_blocks_[p_.objects[d.object].poses[d.pose].keyframe]);
    const Vec3 X_w = to_world(b.pose(pose_block_[d.object][d.pose]), b.point(point_block_[d.object][d.point]));
    const ObservationError err = observation_error(cam_, T_c_w, X_w, d.uv, d.u_right, d.inv_sigma2, opt_.min_depth);
    out[e] = !err.in_front || err.chi2 > threshold(d);
  }
  return out;
}

void DynamicReprojectionTerms::write_back(const ProblemBuilder& b, BAProblem& problem) const {
  for (size_t o = 0; o < problem.objects.size(); ++o) {
    BAObject& obj = problem.objects[o];
    for (size_t k = 0; k < obj.poses.size(); ++k)
      if (pose_block_[o][k] >= 0 && !obj.poses[k].fixed) obj.poses[k].T_w_o = b.pose(pose_block_[o][k]);
    for (size_t j = 0; j < obj.points_o.size(); ++j)
      if (point_block_[o][j] >= 0) obj.points_o[j] = b.point(point_block_[o][j]);
  }
}

}  // namespace twistslam::optim::detail
