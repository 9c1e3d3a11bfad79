// Keyframes and the local map: when to take a keyframe (TwistSLAM's temporal and spatial
// criteria), new stereo points, culling, and the local bundle adjustment (static half of
// paper eq. 9).
#include <algorithm>
#include <chrono>
#include <unordered_map>
#include <unordered_set>

#include "optim/bundle_adjustment.hpp"
#include "tracking/system.hpp"

namespace twistslam::tracking {
namespace {
// ORB-SLAM2 requires this many tracked inliers before a keyframe is worth adding.
constexpr int kMinKeyframeInliers = 15;
}  // namespace

int System::count_initial_points(const Frame& frame) const {
  int n = 0;
  for (size_t i = 0; i < frame.keypoints.size(); ++i) n += frame.usable[i] && frame.keypoints.has_depth(i);
  return n;
}

void System::start_segment(Frame& frame) {
  ++segment_;
  const int kf = insert_keyframe(frame);
  segment_first_keyframe_ = kf;
  reference_keyframe_ = kf;
}

bool System::need_keyframe(const Frame& frame) const {
  const int inliers = frame.num_matched_inliers();
  if (inliers < kMinKeyframeInliers || reference_keyframe_ < 0) return false;
  const double close_depth = options_.tracking.close_depth_baselines * camera_.baseline;
  int close_tracked = 0, close_new = 0;
  for (size_t i = 0; i < frame.keypoints.size(); ++i) {
    const double d = frame.keypoints.depth[i];
    if (d <= 0 || d >= close_depth || !frame.usable[i]) continue;
    if (frame.point_ids[i] >= 0 && !frame.outlier[i]) ++close_tracked;
    else ++close_new;
  }
  const KeyframeOptions& k = options_.keyframes;
  const bool temporal = frame.index - last_keyframe_frame_ >= k.max_frames_between;
  // Reference: the keyframe's established points (seen by >= 2 keyframes, 3 once the map has
  // more than 2), not its fresh stereo points most of which the next frames never re-match.
  const size_t min_obs = map_.num_keyframes() > 2 ? 3 : 2;
  int reference_points = 0;
  for (int pid : map_.keyframe(reference_keyframe_).point_ids)
    reference_points += pid >= 0 && map_.point(pid).observations.size() >= min_obs;
  const bool spatial = inliers < k.min_tracked_ratio * reference_points;
  const bool structure = close_tracked < k.min_close_tracked && close_new > k.min_new_close;
  return temporal || spatial || structure;
}

int System::insert_keyframe(Frame& frame) {
  map::KeyFrame kf;
  kf.frame_index = frame.index;
  kf.timestamp = frame.timestamp;
  kf.T_c_w = frame.T_c_w;
  kf.keypoints = frame.keypoints;
  kf.segment = segment_;
  const int id = map_.add_keyframe(std::move(kf)).id;
  for (size_t i = 0; i < frame.point_ids.size(); ++i) {
    const int pid = frame.point_ids[i];
    if (pid < 0) continue;
    if (frame.outlier[i]) {
      frame.point_ids[i] = -1;
      frame.outlier[i] = 0;
      continue;
    }
    map_.add_observation(pid, id, static_cast<int>(i));
    map_.update_descriptor(pid);
  }
  create_stereo_points(frame, id);
  map_.update_covisibility(id);
  reference_keyframe_ = id;
  last_keyframe_frame_ = frame.index;
  cull_recent_points(id);
  local_bundle_adjustment(id);
  bound_map_size();
  return id;
}

int System::create_stereo_points(Frame& frame, int keyframe_id) {
  // Every stereo match becomes a point, far ones included: points beyond ORB-SLAM's 40
  // baselines carry little depth but pin the rotation (on the simulator, keeping only close
  // points doubled the per-frame rotation error). Their disparity residual keeps a constant
  // pixel noise, so the BA weighs them correctly.
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  int created = 0;
  for (size_t k = 0; k < frame.keypoints.size(); ++k) {
    if (!frame.usable[k] || !frame.keypoints.has_depth(k) || frame.point_ids[k] >= 0) continue;
    const int i = static_cast<int>(k);
    const Vec3 X_c = camera_.backproject(frame.keypoints.uv[i], frame.keypoints.depth[i]);
    map::MapPoint& p = map_.add_point(T_w_c.topLeftCorner<3, 3>() * X_c + T_w_c.topRightCorner<3, 1>(),
                                      frame.keypoints.descriptors[i], keyframe_id);
    p.label = frame.keypoints.label[i];
    map_.add_observation(p.id, keyframe_id, i);
    frame.point_ids[i] = p.id;  // the next frame tracks them through the motion model
    recent_points_.push_back(p.id);
    ++created;
  }
  return created;
}

void System::cull_recent_points(int keyframe_id) {
  const MapOptions& m = options_.map;
  std::vector<int> keep;
  for (int pid : recent_points_) {
    if (!map_.has_point(pid)) continue;
    const map::MapPoint& p = map_.point(pid);
    const int age = keyframe_id - p.first_keyframe;
    if (p.bad || p.found_ratio() < m.min_found_ratio ||
        (age >= m.cull_after_keyframes && p.observations.size() < 2)) {
      map_.erase_point(pid);
    } else if (age < m.cull_after_keyframes + 1) {
      keep.push_back(pid);  // still on probation
    }
  }
  recent_points_ = std::move(keep);
}

void System::local_bundle_adjustment(int keyframe_id) {
  const auto start = std::chrono::steady_clock::now();
  const LocalBAOptions& o = options_.local_ba;
  const int segment = map_.keyframe(keyframe_id).segment;
  std::vector<int> window{keyframe_id};
  for (int kf : map_.covisible_keyframes(keyframe_id, o.window - 1))
    if (map_.keyframe(kf).segment == segment) window.push_back(kf);
  if (window.size() < 2) return;  // a lone keyframe: nothing to adjust against

  optim::BAProblem problem;
  std::unordered_map<int, int> kf_slot;
  for (int kf : window) {
    kf_slot[kf] = static_cast<int>(problem.keyframes.size());
    problem.keyframes.push_back({map_.keyframe(kf).T_c_w, kf == segment_first_keyframe_});
  }
  std::vector<int> candidates;  // points of the window, each once
  {
    std::unordered_set<int> seen;
    for (int kf : window)
      for (int pid : map_.keyframe(kf).point_ids)
        if (pid >= 0 && seen.insert(pid).second) candidates.push_back(pid);
  }
  // Fixed keyframes: others seeing the window's points, most shared first.
  std::unordered_map<int, int> shared;
  for (int pid : candidates)
    for (const auto& obs : map_.point(pid).observations)
      if (!kf_slot.count(obs.first) && map_.keyframe(obs.first).segment == segment) ++shared[obs.first];
  std::vector<std::pair<int, int>> ranked;
  for (const auto& [kf, n] : shared) ranked.emplace_back(n, kf);
  std::sort(ranked.rbegin(), ranked.rend());
  for (size_t k = 0; k < ranked.size() && static_cast<int>(k) < o.max_fixed; ++k) {
    kf_slot[ranked[k].second] = static_cast<int>(problem.keyframes.size());
    problem.keyframes.push_back({map_.keyframe(ranked[k].second).T_c_w, true});
  }
  // Gauge: without a fixed keyframe the window would float; hold its oldest one.
  if (std::none_of(problem.keyframes.begin(), problem.keyframes.end(), [](const auto& k) { return k.fixed; })) {
    const int oldest = *std::min_element(window.begin(), window.end());
    problem.keyframes[kf_slot[oldest]].fixed = true;
  }

  // Points seen by at least two keyframes of the problem. A point seen once is exactly
  // determined by its own observation (stereo) or not at all (mono): its Schur complement
  // is zero, so it tells the poses nothing and only costs solver time (~half of the window's points).
  std::vector<int> point_ids;
  std::vector<std::pair<int, int>> obs_link;  // (point id, keyframe id) per observation
  for (int pid : candidates) {
    const auto& observations = map_.point(pid).observations;
    const long in_problem = std::count_if(observations.begin(), observations.end(),
                                          [&](const auto& obs) { return kf_slot.count(obs.first) > 0; });
    if (in_problem < 2) continue;
    const int slot = static_cast<int>(problem.points.size());
    problem.points.push_back({map_.point(pid).X_w, false});
    point_ids.push_back(pid);
    for (const auto& [kf, kp] : observations) {
      const auto kf_it = kf_slot.find(kf);
      if (kf_it == kf_slot.end()) continue;
      const map::StereoKeypoints& k = map_.keyframe(kf).keypoints;
      problem.observations.push_back({kf_it->second, slot, k.uv[kp], k.u_right[kp],
                                      inv_level_sigma2_[std::min<size_t>(k.octave[kp], inv_level_sigma2_.size() - 1)]});
      obs_link.emplace_back(pid, kf);
    }
  }

  optim::BundleAdjustmentOptions ba;
  ba.max_iterations_first = o.iterations_first;
  ba.max_iterations_second = o.iterations_second;
  ba.huber_delta_stereo = o.huber_stereo;
  ba.huber_delta_mono = o.huber_mono;
  ba.num_threads = o.num_threads;
  const optim::BundleAdjustmentReport report = optim::bundle_adjust(problem, camera_, ba);

  for (const auto& [kf, slot] : kf_slot)
    if (!problem.keyframes[slot].fixed) map_.keyframe(kf).T_c_w = problem.keyframes[slot].T_c_w;
  for (size_t k = 0; k < point_ids.size(); ++k) map_.point(point_ids[k]).X_w = problem.points[k].X_w;
  std::unordered_set<int> touched;
  for (size_t e = 0; e < obs_link.size(); ++e) {
    if (e < report.outlier.size() && report.outlier[e]) {
      map_.erase_observation(obs_link[e].first, obs_link[e].second);
      touched.insert(obs_link[e].first);
    }
  }
  for (int pid : touched)
    if (map_.point(pid).observations.empty()) map_.erase_point(pid);
  for (int kf : window) map_.update_covisibility(kf);
  last_ba_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void System::bound_map_size() {
  const size_t max_points = static_cast<size_t>(std::max(0, options_.map.max_points));
  if (max_points == 0 || map_.num_points() <= max_points) return;
  // Drop the points whose newest observation is oldest: the part of the map left behind.
  std::vector<std::pair<int, int>> age;  // (newest keyframe id, point id)
  for (const auto& [pid, p] : map_.points())
    age.emplace_back(p.observations.empty() ? -1 : p.observations.rbegin()->first, pid);
  const size_t excess = map_.num_points() - max_points;
  std::nth_element(age.begin(), age.begin() + excess, age.end());
  for (size_t k = 0; k < excess; ++k) map_.erase_point(age[k].second);
}

}  // namespace twistslam::tracking
