#include "tracking/local_mapper.hpp"

#include <algorithm>
#include <chrono>
#include <system_error>
#include <utility>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "tracking/local_bundle_adjustment.hpp"

namespace twistslam::tracking {

struct LocalMapper::PendingBA {
  LocalBAJob job;
  std::thread worker;
  std::exception_ptr error;
};

namespace {
// ORB-SLAM2 requires this many tracked inliers before a keyframe is worth adding.
constexpr int kMinKeyframeInliers = 15;

// Whether the camera moved or turned past the temporal rule's floor since `reference`.
bool moved_since(const Frame& frame, const map::KeyFrame& reference, const KeyframeOptions& k) {
  const Mat4 T_ref_c = reference.T_c_w * geometry::se3_inverse(frame.T_c_w);
  const double angle_deg = geometry::so3_log(T_ref_c.topLeftCorner<3, 3>()).norm() * 180.0 / M_PI;
  return T_ref_c.topRightCorner<3, 1>().norm() >= k.temporal_min_translation_m ||
         angle_deg >= k.temporal_min_rotation_deg;
}
}  // namespace

LocalMapper::LocalMapper(const geometry::StereoCamera& camera, const SlamOptions& options, LevelWeights weights)
    : camera_(camera), tracking_options_(options.tracking), keyframe_options_(options.keyframes),
      ba_options_(options.local_ba), map_options_(options.map), weights_(std::move(weights)) {}

LocalMapper::~LocalMapper() { join_worker(); }

void LocalMapper::join_worker() {
  if (pending_ && pending_->worker.joinable()) pending_->worker.join();
}

void LocalMapper::reset() {
  join_worker();
  pending_.reset();
  segment_ = segment_first_keyframe_ = last_keyframe_frame_ = -1;
  recent_points_.clear();
}

bool LocalMapper::can_start_segment(const Frame& frame) const {
  int n = 0;
  for (size_t i = 0; i < frame.keypoints.size(); ++i) n += frame.usable[i] && frame.keypoints.has_depth(i);
  return n >= tracking_options_.min_init_points;
}

KeyframeInsertion LocalMapper::start_segment(Frame& frame, map::Map& map) {
  ++segment_;
  const KeyframeInsertion insertion = insert_keyframe(frame, map);
  segment_first_keyframe_ = insertion.keyframe_id;
  return insertion;
}

bool LocalMapper::need_keyframe(const Frame& frame, const map::Map& map, int reference_keyframe) const {
  const int inliers = frame.num_matched_inliers();
  if (inliers < kMinKeyframeInliers || reference_keyframe < 0) return false;
  const double close_depth = tracking_options_.close_depth_baselines * camera_.baseline;
  int close_tracked = 0, close_new = 0;
  for (size_t i = 0; i < frame.keypoints.size(); ++i) {
    const double d = frame.keypoints.depth[i];
    if (d <= 0 || d >= close_depth || !frame.usable[i]) continue;
    if (frame.point_ids[i] >= 0 && !frame.outlier[i]) ++close_tracked;
    else ++close_new;
  }
  const KeyframeOptions& k = keyframe_options_;
  const bool temporal = frame.index - last_keyframe_frame_ >= k.max_frames_between &&
                        moved_since(frame, map.keyframe(reference_keyframe), k);
  // Reference: the keyframe's established points (seen by >= 2 keyframes, 3 once the map has
  // more than 2), not its fresh stereo points most of which the next frames never re-match.
  const size_t min_obs = map.num_keyframes() > 2 ? 3 : 2;
  int reference_points = 0;
  for (int pid : map.keyframe(reference_keyframe).point_ids)
    reference_points += pid >= 0 && map.point(pid).observations.size() >= min_obs;
  const bool spatial = inliers < k.min_tracked_ratio * reference_points;
  const bool structure = close_tracked < k.min_close_tracked && close_new > k.min_new_close;
  return temporal || spatial || structure;
}

KeyframeInsertion LocalMapper::insert_keyframe(Frame& frame, map::Map& map, ObjectBundleTerms* objects) {
  map::KeyFrame kf;
  kf.frame_index = frame.index;
  kf.timestamp = frame.timestamp;
  kf.T_c_w = frame.T_c_w;
  kf.keypoints = frame.keypoints;
  kf.segment = segment_;
  KeyframeInsertion insertion;
  const int id = insertion.keyframe_id = map.add_keyframe(std::move(kf)).id;
  for (size_t i = 0; i < frame.point_ids.size(); ++i) {
    const int pid = frame.point_ids[i];
    if (pid < 0) continue;
    if (frame.outlier[i]) {
      frame.point_ids[i] = -1;
      frame.outlier[i] = 0;
      continue;
    }
    map.add_observation(pid, id, static_cast<int>(i));
    map.update_descriptor(pid);
  }
  insertion.new_points = create_stereo_points(frame, map, id);
  map.update_covisibility(id);
  last_keyframe_frame_ = frame.index;
  cull_recent_points(map, id);
  if (ba_options_.asynchronous) {
    auto pending = std::make_unique<PendingBA>();
    if (prepare_local_ba(map, id, segment_first_keyframe_, ba_options_, weights_, objects, &pending->job)) {
      PendingBA* p = pending.get();
      // the thread reads only the job and copies of the camera and options
      try {
        p->worker = std::thread([p, camera = camera_, options = ba_options_] {
          try {
            solve_local_ba(camera, options, &p->job);
          } catch (...) {
            p->error = std::current_exception();
          }
        });
      } catch (const std::system_error&) {  // no thread to be had: solve it here
        solve_local_ba(camera_, ba_options_, &p->job);
      }
      pending_ = std::move(pending);
      insertion.ba_pending = true;
      return insertion;  // the map bound follows the BA (finish_bundle_adjustment)
    }
  } else {
    const auto ba_start = std::chrono::steady_clock::now();
    insertion.bundle_adjusted =
        local_bundle_adjustment(map, id, segment_first_keyframe_, camera_, ba_options_, weights_, objects);
    if (insertion.bundle_adjusted)
      insertion.ba_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - ba_start).count();
  }
  bound_map_size(map);
  return insertion;
}

FinishedBundleAdjustment LocalMapper::finish_bundle_adjustment(map::Map& map) {
  FinishedBundleAdjustment done;
  if (!pending_) return done;
  const auto wait_start = std::chrono::steady_clock::now();
  join_worker();
  done.wait_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wait_start).count();
  const std::unique_ptr<PendingBA> pending = std::move(pending_);
  if (pending->error) std::rethrow_exception(pending->error);
  apply_local_ba(pending->job, map);
  bound_map_size(map);
  done.applied = true;
  done.keyframe_id = pending->job.keyframe_id;
  done.frame_index = pending->job.frame_index;
  done.solve_ms = pending->job.solve_ms;
  return done;
}

int LocalMapper::create_stereo_points(Frame& frame, map::Map& map, int keyframe_id) {
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
    map::MapPoint& p = map.add_point(T_w_c.topLeftCorner<3, 3>() * X_c + T_w_c.topRightCorner<3, 1>(),
                                     frame.keypoints.descriptors[i], keyframe_id);
    p.label = frame.keypoints.label[i];
    map.add_observation(p.id, keyframe_id, i);
    frame.point_ids[i] = p.id;  // the next frame tracks them through the motion model
    recent_points_.push_back(p.id);
    ++created;
  }
  return created;
}

void LocalMapper::cull_recent_points(map::Map& map, int keyframe_id) {
  const MapOptions& m = map_options_;
  std::vector<int> keep;
  for (int pid : recent_points_) {
    if (!map.has_point(pid)) continue;
    const map::MapPoint& p = map.point(pid);
    const int age = keyframe_id - p.first_keyframe;
    if (p.bad || p.found_ratio() < m.min_found_ratio ||
        (age >= m.cull_after_keyframes && p.observations.size() < 2)) {
      map.erase_point(pid);
    } else if (age < m.cull_after_keyframes + 1) {
      keep.push_back(pid);  // still on probation
    }
  }
  recent_points_ = std::move(keep);
}

void LocalMapper::bound_map_size(map::Map& map) const {
  const size_t max_points = static_cast<size_t>(std::max(0, map_options_.max_points));
  if (max_points == 0 || map.num_points() <= max_points) return;
  // Drop the points whose newest observation is oldest: the part of the map left behind.
  std::vector<std::pair<int, int>> age;  // (newest keyframe id, point id)
  for (const auto& [pid, p] : map.points())
    age.emplace_back(p.observations.empty() ? -1 : p.observations.rbegin()->first, pid);
  const size_t excess = map.num_points() - max_points;
  std::nth_element(age.begin(), age.begin() + excess, age.end());
  for (size_t k = 0; k < excess; ++k) map.erase_point(age[k].second);
}

}  // namespace twistslam::tracking
