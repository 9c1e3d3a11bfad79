// Camera tracking on static map points (paper eq. 3): the motion-model search, the
// local-map search and the robust pose-only optimisation between them.
#include <algorithm>
#include <unordered_map>

#include "optim/pose_optimization.hpp"
#include "tracking/projection_matcher.hpp"
#include "tracking/system.hpp"

namespace twistslam::tracking {
namespace {
// ORB-SLAM's counts: fewer matches than this and the pose cannot be trusted.
constexpr int kMinMotionMatches = 20;
constexpr int kMinMotionInliers = 10;
// Local keyframes: those observing the frame's points plus this many neighbours each.
constexpr int kNeighboursPerKeyframe = 10;
constexpr int kMaxLocalKeyframes = 80;
}  // namespace

int System::optimize_frame_pose(Frame& frame, bool drop_outliers) {
  std::vector<optim::StereoObservation> obs;
  std::vector<int> index;
  for (size_t i = 0; i < frame.point_ids.size(); ++i) {
    const int pid = frame.point_ids[i];
    if (pid < 0) continue;
    optim::StereoObservation o;
    o.point_w = map_.point(pid).X_w;
    o.uv = frame.keypoints.uv[i];
    o.u_right = frame.keypoints.u_right[i];
    o.inv_sigma2 = inv_level_sigma2_[std::min<size_t>(frame.keypoints.octave[i], inv_level_sigma2_.size() - 1)];
    obs.push_back(o);
    index.push_back(static_cast<int>(i));
  }
  if (obs.empty()) return 0;
  optim::PoseOptimizationOptions opts;
  opts.rounds = options_.tracking.pose_rounds;
  opts.chi2_stereo = options_.tracking.chi2_stereo;
  opts.chi2_mono = options_.tracking.chi2_mono;
  const optim::PoseOptimizationResult r = optim::optimize_pose(frame.T_c_w, obs, camera_, opts);
  if (!r.converged) return 0;
  frame.T_c_w = r.T_c_w;
  int inliers = 0;
  for (size_t k = 0; k < index.size(); ++k) {
    const int i = index[k];
    frame.outlier[i] = !r.inlier[k];
    if (r.inlier[k]) {
      ++inliers;
    } else if (drop_outliers) {
      frame.point_ids[i] = -1;
      frame.outlier[i] = 0;
    }
  }
  return inliers;
}

bool System::track_with_motion_model(Frame& frame, double radius_scale) {
  std::vector<int> last_points;
  for (size_t i = 0; i < last_frame_.point_ids.size(); ++i) {
    const int pid = last_frame_.point_ids[i];
    if (pid >= 0 && !last_frame_.outlier[i] && map_.has_point(pid)) last_points.push_back(pid);
  }
  ProjectionSearch search{options_.tracking.search_radius_px * radius_scale, options_.tracking.max_hamming,
                          options_.tracking.ratio_test};
  frame.clear_matches();
  int matches = search_by_projection(frame, map_, last_points, camera_, extractor_.scale_factors(), search);
  if (matches < kMinMotionMatches) {  // fast or unexpected motion: a wider window
    frame.clear_matches();
    search.radius_px *= 2;
    matches = search_by_projection(frame, map_, last_points, camera_, extractor_.scale_factors(), search);
  }
  if (matches < kMinMotionMatches) return false;
  return optimize_frame_pose(frame, /*drop_outliers=*/true) >= kMinMotionInliers;
}

bool System::relocalize_in_local_map(Frame& frame) {
  // After a loss the last frame has no matches to follow: search the local map of the last
  // tracked frame from the predicted pose, in twice the motion model's window. Short losses
  // (a blank frame, a truck filling the view) resume in the same map instead of a new one.
  std::vector<int> points;
  std::unordered_map<int, bool> seen;
  for (int kf : local_keyframes_) {
    if (!map_.has_keyframe(kf)) continue;
    for (int pid : map_.keyframe(kf).point_ids)
      if (pid >= 0 && !seen[pid] && map_.has_point(pid)) points.push_back(pid), seen[pid] = true;
  }
  if (points.empty()) return false;
  const ProjectionSearch search{options_.tracking.search_radius_px * 2, options_.tracking.max_hamming,
                                options_.tracking.ratio_test};
  frame.clear_matches();
  if (search_by_projection(frame, map_, points, camera_, extractor_.scale_factors(), search) < kMinMotionMatches)
    return false;
  return optimize_frame_pose(frame, /*drop_outliers=*/true) >= kMinMotionInliers;
}

bool System::track_local_map(Frame& frame) {
  // Local keyframes: every keyframe seeing a matched point, ranked by how many it sees.
  std::unordered_map<int, int> votes;
  for (int pid : frame.point_ids)
    if (pid >= 0)
      for (const auto& obs : map_.point(pid).observations) ++votes[obs.first];
  if (votes.empty()) return false;
  std::vector<std::pair<int, int>> ranked(votes.begin(), votes.end());
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first > b.first;
  });
  reference_keyframe_ = ranked.front().first;
  local_keyframes_.clear();
  std::unordered_map<int, bool> chosen;
  for (const auto& [kf, _] : ranked) {
    if (static_cast<int>(local_keyframes_.size()) >= kMaxLocalKeyframes) break;
    if (!chosen[kf]) local_keyframes_.push_back(kf), chosen[kf] = true;
  }
  const size_t direct = local_keyframes_.size();
  for (size_t k = 0; k < direct && static_cast<int>(local_keyframes_.size()) < kMaxLocalKeyframes; ++k)
    for (int nb : map_.covisible_keyframes(local_keyframes_[k], kNeighboursPerKeyframe))
      if (!chosen[nb] && static_cast<int>(local_keyframes_.size()) < kMaxLocalKeyframes)
        local_keyframes_.push_back(nb), chosen[nb] = true;

  // Local points: what those keyframes see; already matched ones count as visible.
  std::vector<int> local_points;
  std::unordered_map<int, bool> seen;
  for (int pid : frame.point_ids)
    if (pid >= 0) ++map_.point(pid).visible, seen[pid] = true;
  for (int kf : local_keyframes_)
    for (int pid : map_.keyframe(kf).point_ids)
      if (pid >= 0 && !seen[pid]) local_points.push_back(pid), seen[pid] = true;

  const ProjectionSearch search{options_.tracking.local_map_search_radius_px, options_.tracking.max_hamming,
                                options_.tracking.ratio_test};
  search_by_projection(frame, map_, local_points, camera_, extractor_.scale_factors(), search,
                       /*count_visible=*/true);
  const int inliers = optimize_frame_pose(frame, /*drop_outliers=*/false);
  for (size_t i = 0; i < frame.point_ids.size(); ++i)
    if (frame.point_ids[i] >= 0 && !frame.outlier[i]) ++map_.point(frame.point_ids[i]).found;
  return inliers >= options_.tracking.min_inliers;
}

}  // namespace twistslam::tracking
