#include "tracking/camera_tracker.hpp"

#include <algorithm>
#include <unordered_map>
#include <utility>

#include "geometry/se3.hpp"
#include "optim/pose_optimization.hpp"
#include "tracking/descriptor_pose.hpp"
#include "tracking/projection_matcher.hpp"

namespace twistslam::tracking {
namespace {
// ORB-SLAM's counts: fewer matches than this and the pose cannot be trusted.
constexpr int kMinMotionMatches = 20;
constexpr int kMinMotionInliers = 10;
// Local keyframes: those observing the frame's points plus this many neighbours each.
constexpr int kNeighboursPerKeyframe = 10;
constexpr int kMaxLocalKeyframes = 80;
}  // namespace

CameraTracker::CameraTracker(const geometry::StereoCamera& camera, const TrackingOptions& options,
                             std::vector<float> scale_factors, LevelWeights weights)
    : camera_(camera), options_(options), scale_factors_(std::move(scale_factors)),
      weights_(std::move(weights)) {}

void CameraTracker::reset() {
  has_last_ = false;
  velocity_ = Mat4::Identity();
  has_velocity_ = false;
  local_keyframes_.clear();
}

Mat4 CameraTracker::predicted_pose() const {
  if (!has_last_) return Mat4::Identity();
  return velocity_ * last_frame_.T_c_w;  // constant velocity
}

void CameraTracker::update_velocity(const Frame& frame) {
  if (!has_last_) return;
  velocity_ = frame.T_c_w * geometry::se3_inverse(last_frame_.T_c_w);
  has_velocity_ = true;
}

void CameraTracker::set_last_frame(Frame frame) {
  last_frame_ = std::move(frame);
  has_last_ = true;
}

void CameraTracker::refine_last_frame_pose(int frame_index, const Mat4& T_c_w) {
  if (has_last_ && last_frame_.index == frame_index) last_frame_.T_c_w = T_c_w;
}

bool CameraTracker::track_motion(Frame& frame, map::Map& map, bool after_loss) {
  // After a loss the last frame has no matches: relocalise in the last local map instead.
  // Without a velocity (the frame after a map start) the prediction is "no motion", off by a
  // whole frame of driving: search four times as wide.
  if (after_loss) return relocalize_in_local_map(frame, map);
  if (!has_velocity_ && options_.descriptor_prediction) predict_from_descriptors(frame, map);
  if (track_with_motion_model(frame, map, has_velocity_ ? 1.0 : 4.0)) return true;
  // The motion model lost its matches (an unexpected motion): try the local map before
  // giving up on this map.
  return relocalize_in_local_map(frame, map);
}

int CameraTracker::optimize_frame_pose(Frame& frame, const map::Map& map, bool drop_outliers) {
  std::vector<optim::StereoObservation> obs;
  std::vector<int> index;
  for (size_t i = 0; i < frame.point_ids.size(); ++i) {
    const int pid = frame.point_ids[i];
    if (pid < 0) continue;
    optim::StereoObservation o;
    o.point_w = map.point(pid).X_w;
    o.uv = frame.keypoints.uv[i];
    o.u_right = frame.keypoints.u_right[i];
    o.inv_sigma2 = weights_.at(frame.keypoints.octave[i]);
    obs.push_back(o);
    index.push_back(static_cast<int>(i));
  }
  if (obs.empty()) return 0;
  optim::PoseOptimizationOptions opts;
  opts.rounds = options_.pose_rounds;
  opts.chi2_stereo = options_.chi2_stereo;
  opts.chi2_mono = options_.chi2_mono;
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

std::vector<int> CameraTracker::last_frame_points(const map::Map& map) const {
  std::vector<int> points;
  for (size_t i = 0; i < last_frame_.point_ids.size(); ++i) {
    const int pid = last_frame_.point_ids[i];
    if (pid >= 0 && !last_frame_.outlier[i] && map.has_point(pid)) points.push_back(pid);
  }
  return points;
}

void CameraTracker::predict_from_descriptors(Frame& frame, const map::Map& map) const {
  // The frame after a map start has no velocity: "no motion" is a whole frame of driving off,
  // and even the 4x window then matches mostly far points near the image centre, which barely
  // see the forward motion (urban s13: the first step came out 0.43 m short of 1.20 m with 181
  // static inliers at a median depth of 37 m). Descriptor matches to the last frame's points,
  // without a position prior, and PnP RANSAC give the search a prediction that holds the motion.
  DescriptorPoseOptions options;
  options.max_hamming = options_.max_hamming;
  options.ratio_test = options_.ratio_test;
  options.min_inliers = kMinMotionMatches;
  const std::optional<DescriptorPose> pose =
      pose_from_descriptors(frame, map, last_frame_points(map), camera_, options);
  if (pose) frame.T_c_w = pose->T_c_w;
}

bool CameraTracker::track_with_motion_model(Frame& frame, map::Map& map, double radius_scale) {
  const std::vector<int> last_points = last_frame_points(map);
  ProjectionSearch search{options_.search_radius_px * radius_scale, options_.max_hamming,
                          options_.ratio_test};
  frame.clear_matches();
  int matches = search_by_projection(frame, map, last_points, camera_, scale_factors_, search);
  if (matches < kMinMotionMatches) {  // fast or unexpected motion: a wider window
    frame.clear_matches();
    search.radius_px *= 2;
    matches = search_by_projection(frame, map, last_points, camera_, scale_factors_, search);
  }
  if (matches < kMinMotionMatches) return false;
  return optimize_frame_pose(frame, map, /*drop_outliers=*/true) >= kMinMotionInliers;
}

bool CameraTracker::relocalize_in_local_map(Frame& frame, map::Map& map) {
  // After a loss the last frame has no matches to follow: search the local map of the last
  // tracked frame from the predicted pose, in twice the motion model's window. Short losses
  // (a blank frame, a truck filling the view) resume in the same map instead of a new one.
  std::vector<int> points;
  std::unordered_map<int, bool> seen;
  for (int kf : local_keyframes_) {
    if (!map.has_keyframe(kf)) continue;
    for (int pid : map.keyframe(kf).point_ids)
      if (pid >= 0 && !seen[pid] && map.has_point(pid)) points.push_back(pid), seen[pid] = true;
  }
  if (points.empty()) return false;
  const ProjectionSearch search{options_.search_radius_px * 2, options_.max_hamming,
                                options_.ratio_test};
  frame.clear_matches();
  if (search_by_projection(frame, map, points, camera_, scale_factors_, search) < kMinMotionMatches)
    return false;
  return optimize_frame_pose(frame, map, /*drop_outliers=*/true) >= kMinMotionInliers;
}

LocalMapTracking CameraTracker::track_local_map(Frame& frame, map::Map& map) {
  // Local keyframes: every keyframe seeing a matched point, ranked by how many it sees.
  std::unordered_map<int, int> votes;
  for (int pid : frame.point_ids)
    if (pid >= 0)
      for (const auto& obs : map.point(pid).observations) ++votes[obs.first];
  LocalMapTracking result;
  if (votes.empty()) return result;
  std::vector<std::pair<int, int>> ranked(votes.begin(), votes.end());
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first > b.first;
  });
  result.reference_keyframe = ranked.front().first;
  local_keyframes_.clear();
  std::unordered_map<int, bool> chosen;
  for (const auto& [kf, _] : ranked) {
    if (static_cast<int>(local_keyframes_.size()) >= kMaxLocalKeyframes) break;
    if (!chosen[kf]) local_keyframes_.push_back(kf), chosen[kf] = true;
  }
  const size_t direct = local_keyframes_.size();
  for (size_t k = 0; k < direct && static_cast<int>(local_keyframes_.size()) < kMaxLocalKeyframes; ++k)
    for (int nb : map.covisible_keyframes(local_keyframes_[k], kNeighboursPerKeyframe))
      if (!chosen[nb] && static_cast<int>(local_keyframes_.size()) < kMaxLocalKeyframes)
        local_keyframes_.push_back(nb), chosen[nb] = true;

  // Local points: what those keyframes see; already matched ones count as visible.
  std::vector<int> local_points;
  std::unordered_map<int, bool> seen;
  for (int pid : frame.point_ids)
    if (pid >= 0) ++map.point(pid).visible, seen[pid] = true;
  for (int kf : local_keyframes_)
    for (int pid : map.keyframe(kf).point_ids)
      if (pid >= 0 && !seen[pid]) local_points.push_back(pid), seen[pid] = true;

  const ProjectionSearch search{options_.local_map_search_radius_px, options_.max_hamming,
                                options_.ratio_test};
  search_by_projection(frame, map, local_points, camera_, scale_factors_, search,
                       /*count_visible=*/true);
  const int inliers = optimize_frame_pose(frame, map, /*drop_outliers=*/false);
  for (size_t i = 0; i < frame.point_ids.size(); ++i)
    if (frame.point_ids[i] >= 0 && !frame.outlier[i]) ++map.point(frame.point_ids[i]).found;
  result.tracked = inliers >= options_.min_inliers;
  return result;
}

}  // namespace twistslam::tracking
