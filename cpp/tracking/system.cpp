#include "tracking/system.hpp"

#include <chrono>
#include <map>
#include <stdexcept>
#include <utility>

#include "geometry/se3.hpp"
#include "tracking/road_lidar_points.hpp"

namespace twistslam::tracking {
namespace {

class StageTimer {
 public:
  explicit StageTimer(TrackResult* r) : result_(r), start_(std::chrono::steady_clock::now()) {}
  void lap(const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    result_->timings_ms.emplace_back(stage, std::chrono::duration<double, std::milli>(now - start_).count());
    start_ = now;
  }

 private:
  TrackResult* result_;
  std::chrono::steady_clock::time_point start_;
};

// The road plane's options from the visual objects' (the rest are RoadPlaneOptions' defaults).
objects::RoadPlaneOptions road_plane_options(const ObjectTrackingOptions& o) {
  objects::RoadPlaneOptions road;
  road.window_m = o.road_plane_window_m;
  return road;
}

}  // namespace

const char* to_string(Status status) {
  switch (status) {
    case Status::kInitialized: return "initialized";
    case Status::kOk: return "ok";
    case Status::kLost: return "lost";
    case Status::kRelocalized: return "relocalized";
  }
  return "unknown";
}

System::System(const geometry::StereoCamera& camera, const SlamOptions& options)
    : options_((check_options(options), options)),  // the same ranges as from Python
      camera_(camera),
      frame_builder_(camera, options),
      camera_tracker_(camera, options.tracking, frame_builder_.extractor().scale_factors(),
                      LevelWeights(frame_builder_.extractor().level_sigma2())),
      local_mapper_(camera, options, LevelWeights(frame_builder_.extractor().level_sigma2())),
      object_tracker_(camera, options.visual_objects, frame_builder_.extractor().scale_factors(),
                      LevelWeights(frame_builder_.extractor().level_sigma2()),
                      options.lidar_objects),
      road_plane_(road_plane_options(options.visual_objects)) {}

void System::reset() {
  local_mapper_.reset();  // drops a pending BA before the map it refers to
  finished_ba_ = FinishedBundleAdjustment();
  map_.clear();
  road_plane_ = objects::RoadPlaneEstimator(road_plane_options(options_.visual_objects));
  road_up_w_ = Vec3(0, -1, 0);
  camera_tracker_.reset();
  local_mapper_.reset();
  object_tracker_.reset();
  state_ = State::kEmpty;
  reference_keyframe_ = -1;
  trajectory_.clear();
}

TrackResult System::track(int index, double timestamp, const cv::Mat& left, const cv::Mat& right,
                          const cv::Mat& labels, const Points3& points_c,
                          const cv::Mat& instances, const cv::Mat& flow,
                          const std::vector<objects::Detection>& detections) {
  TrackResult result;
  Frame frame;
  const ObjectTrackingOptions& vo = options_.visual_objects;
  cv::Mat object_mask;  // where extra keypoints are extracted (object instances)
  cv::Mat vehicle_instances;  // the instances that may get a second pass (planar-link classes)
  cv::Mat thin_instances;     // people: their edge keypoints' depth from their own pixels
  if (!instances.empty() && vo.enabled && vo.extra_keypoints) {
    if (instances.type() != CV_32SC1 || instances.size() != left.size())
      throw std::invalid_argument("instances: expected int32 instance ids of the image size");
    if (labels.empty() || labels.size() == instances.size()) {
      object_mask = object_class_mask(instances, labels, vo.object_class_ids);
      if (vo.extra_min_instance_keypoints > 0 || vo.pulled_nearer_check || vo.right_occlusion_check) {
        // vehicles only (second pass, pulled-nearer check): a pedestrian's extra points seeded a
        // ghost (crowded seed 0, classical)
        vehicle_instances = instances_of_classes(instances, labels, vo.planar_class_ids);
        if (vo.pulled_nearer_check && !labels.empty())
          mark_occluder_classes(labels, vo.pulled_nearer_occluder_class_ids, &vehicle_instances);
      }
      if (vo.instance_pixel_stereo && !vo.instance_pixel_class_ids.empty())
        thin_instances = instances_of_classes(instances, labels, vo.instance_pixel_class_ids);
    }
  }
  FrameBuildReport built = frame_builder_.build(index, timestamp, left, right, labels, points_c,
                                                &frame, object_mask, vehicle_instances,
                                                thin_instances);
  result.timings_ms = std::move(built.timings_ms);
  result.num_lidar_depth = built.num_lidar_depth;
  // The previous keyframe's BA solved beside the front end above (and, with
  // local_ba.apply_delay_frames, beside the frames tracked since): tracking now needs its map.
  if (local_mapper_.bundle_adjustment_pending()) {
    const bool objects_in_ba = options_.local_ba.dynamic_objects;  // their tracks wait for it
    if (objects_in_ba || frames_since_ba_start_ >= options_.local_ba.apply_delay_frames)
      finish_local_ba();
    else
      ++frames_since_ba_start_;  // this frame is tracked against the map as it was
  }
  StageTimer timer(&result);
  frame.T_c_w = camera_tracker_.predicted_pose();
  bool tracked = false;

  // 1. Camera tracking against the map, once there is one.
  if (state_ != State::kEmpty) {
    tracked = camera_tracker_.track_motion(frame, map_, /*after_loss=*/state_ == State::kLost);
    timer.lap("track_motion");
    if (tracked) {
      const LocalMapTracking local = camera_tracker_.track_local_map(frame, map_);
      if (local.reference_keyframe >= 0) reference_keyframe_ = local.reference_keyframe;
      tracked = local.tracked;
    }
    timer.lap("track_local_map");
    if (tracked) result.status = state_ == State::kLost ? Status::kRelocalized : Status::kOk;
  }
  // 2. Not tracked: the first frame, or a restart after tracking loss, starts a map segment
  // at the predicted pose when it has enough stereo points; otherwise the frame is lost.
  if (!tracked) {
    const bool fresh = state_ == State::kEmpty;
    frame.T_c_w = camera_tracker_.predicted_pose();
    frame.clear_matches();
    if (local_mapper_.can_start_segment(frame)) {
      finish_local_ba();  // the map must not change under a pending BA
      reference_keyframe_ = local_mapper_.start_segment(frame, map_).keyframe_id;
      result.status = fresh ? Status::kInitialized : Status::kRelocalized;
      result.is_keyframe = true;
      tracked = true;
    } else {
      result.status = Status::kLost;
    }
  }
  // 3. Objects: every cluster tracked against the camera pose just found (eq. 4), before
  // local mapping so that a keyframe's BA sees this frame's object observations (e_dyna).
  const bool track_objects = tracked && (!instances.empty() || !object_tracker_.tracks().empty());
  if (track_objects) {
    result.objects = object_tracker_.track(frame, instances, flow, road_up_w_, labels,
                                           road_plane_.plane(), detections,
                                           points_c.rows() > 0 ? &points_c : nullptr,
                                           built.gray_left, built.gray_right);
    if (result.is_keyframe) object_tracker_.mark_keyframe(frame.index, options_.local_ba.window);
    timer.lap("objects");
  }
  // 4. Local mapping: a keyframe when the tracked frame needs one.
  if (tracked) {
    // the velocity of two consecutive tracked frames of one segment, before any BA refines it
    if (state_ == State::kTracking && !result.is_keyframe) camera_tracker_.update_velocity(frame);
    state_ = State::kTracking;
    KeyframeInsertion insertion;
    double insertion_wait_ms = 0;
    if (!result.is_keyframe && local_mapper_.need_keyframe(frame, map_, reference_keyframe_)) {
      const double waited_ms = finished_ba_.wait_ms;
      finish_local_ba();  // the map must not change under a pending BA
      insertion_wait_ms = finished_ba_.wait_ms - waited_ms;
      const bool dynamic = track_objects && options_.local_ba.dynamic_objects;
      if (dynamic) object_tracker_.mark_keyframe(frame.index, options_.local_ba.window);
      insertion = local_mapper_.insert_keyframe(frame, map_, dynamic ? &object_tracker_ : nullptr);
      reference_keyframe_ = insertion.keyframe_id;
      result.is_keyframe = true;
    }
    timer.lap("keyframe");
    // a wait for the previous BA before this insertion is reported apart (local_ba_wait)
    result.timings_ms.back().second -= insertion_wait_ms;
    if (insertion.ba_pending) {
      pending_keyframe_T_c_w_ = frame.T_c_w;
      frames_since_ba_start_ = 0;
    }
    if (insertion.bundle_adjusted) {  // report the BA apart from the rest of the insertion
      result.timings_ms.back().second -= insertion.ba_ms;
      result.timings_ms.emplace_back("local_ba", insertion.ba_ms);
    }
  } else if (state_ != State::kEmpty) {
    state_ = State::kLost;  // keep the velocity: the next prediction continues the motion
  }

  if (tracked && result.is_keyframe && !labels.empty() && options_.visual_objects.road_class_id >= 0) {
    add_road_points(frame, labels, points_c);
    timer.lap("road_plane");
  }

  if (finished_ba_.applied) {  // solved in its own thread; the wait is this frame's
    result.timings_ms.emplace_back("local_ba", finished_ba_.solve_ms);
    result.timings_ms.emplace_back("local_ba_wait", finished_ba_.wait_ms);
    finished_ba_ = FinishedBundleAdjustment();
  }
  record_trajectory(frame, result.status);
  result.T_w_c = geometry::se3_inverse(frame.T_c_w);
  result.num_inliers = frame.num_matched_inliers();
  result.num_map_points = static_cast<int>(map_.num_points());
  result.num_keyframes = static_cast<int>(map_.num_keyframes());
  if (result.is_keyframe && reference_keyframe_ >= 0)  // bundle adjustment refined this frame
    frame.T_c_w = map_.keyframe(reference_keyframe_).T_c_w;
  camera_tracker_.set_last_frame(std::move(frame));
  return result;
}

void System::add_road_points(const Frame& frame, const cv::Mat& labels, const Points3& points_c) {
  const map::StereoKeypoints& k = frame.keypoints;
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  const ObjectTrackingOptions& vo = options_.visual_objects;
  std::vector<Vec3> points;
  for (size_t i = 0; i < k.size(); ++i) {
    if (k.label[i] != vo.road_class_id || !k.has_depth(i) || k.depth[i] > vo.road_max_depth_m) continue;
    points.push_back(T_w_c.topLeftCorner<3, 3>() * camera_.backproject(k.uv[i], k.depth[i]) + T_w_c.topRightCorner<3, 1>());
  }
  if (vo.road_lidar_points && points_c.rows() > 0) {  // the scan's road returns (paper: LiDAR road points)
    const RoadLidarSelection selection{vo.road_class_id, vo.road_lidar_max_depth_m,
                                       vo.road_lidar_border_px, vo.road_lidar_max_points};
    const RoadLidarPoints road = select_road_lidar_points(points_c, camera_, labels, selection);
    for (Eigen::Index i = 0; i < road.points_c.rows(); ++i)
      points.push_back(T_w_c.topLeftCorner<3, 3>() * road.points_c.row(i).transpose() + T_w_c.topRightCorner<3, 1>());
  }
  if (points.empty()) return;
  Points3 rows(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t r = 0; r < points.size(); ++r) rows.row(static_cast<Eigen::Index>(r)) = points[r].transpose();
  road_plane_.add_points(rows, T_w_c.topRightCorner<3, 1>());
  if (road_plane_.valid()) road_up_w_ = road_plane_.normal_up();
}

void System::finish_local_ba() {
  const FinishedBundleAdjustment done = local_mapper_.finish_bundle_adjustment(map_);
  if (!done.applied) return;
  finished_ba_ = done;  // its times go with this or the next frame's result
  // what the synchronous BA refined before the keyframe's track() returned
  camera_tracker_.refine_last_frame_pose(done.frame_index, map_.keyframe(done.keyframe_id).T_c_w);
  for (auto e = trajectory_.rbegin(); e != trajectory_.rend(); ++e) {
    if (e->frame_index != done.frame_index) continue;
    if (e->reference_keyframe == done.keyframe_id)
      e->T_c_r = pending_keyframe_T_c_w_ * map_.keyframe(done.keyframe_id).T_w_c();
    break;
  }
}

void System::record_trajectory(const Frame& frame, Status status) {
  TrajectoryEntry entry{frame.index, frame.timestamp, reference_keyframe_, frame.T_c_w, status};
  if (reference_keyframe_ >= 0) entry.T_c_r = frame.T_c_w * map_.keyframe(reference_keyframe_).T_w_c();
  trajectory_.push_back(entry);
}

const map::Map& System::map() {
  finish_local_ba();
  return map_;
}

const ObjectTracker& System::objects() {
  finish_local_ba();
  return object_tracker_;
}

std::vector<std::pair<TrajectoryEntry, Mat4>> System::trajectory() {
  finish_local_ba();
  std::vector<std::pair<TrajectoryEntry, Mat4>> out;
  out.reserve(trajectory_.size());
  for (const auto& e : trajectory_) {
    Mat4 T_c_w = e.T_c_r;
    if (e.reference_keyframe >= 0 && map_.has_keyframe(e.reference_keyframe))
      T_c_w = e.T_c_r * map_.keyframe(e.reference_keyframe).T_c_w;
    out.emplace_back(e, geometry::se3_inverse(T_c_w));
  }
  return out;
}

ObjectSmoothingReport System::smooth_objects() {
  finish_local_ba();
  // the objects were tracked against each frame's pose as it was then; local BA has refined
  // the keyframes since, and through them every frame (trajectory())
  std::map<int, Mat4> T_c_w_of_frame;
  for (const auto& [entry, T_w_c] : trajectory())
    T_c_w_of_frame[entry.frame_index] = geometry::se3_inverse(T_w_c);
  return object_tracker_.smooth_tracks(T_c_w_of_frame);
}

}  // namespace twistslam::tracking
