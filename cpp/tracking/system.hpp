#pragma once
// The stereo SLAM system, one call per frame. It orchestrates its components: the frame
// builder (features, stereo, labels, LiDAR depth), camera tracking on static points (paper
// eq. 3) and local mapping (keyframes, new points, culling, local BA of eq. 9). Object
// tracking is meant to become a third component beside camera tracking.
// Tracking loss never throws: the frame is flagged lost, the pose is predicted with the
// constant-velocity model, and a new map segment starts from the next good stereo frame.
#include <opencv2/core/mat.hpp>
#include <string>
#include <utility>
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "objects/detection.hpp"
#include "objects/road_plane.hpp"
#include "tracking/camera_tracker.hpp"
#include "tracking/frame_builder.hpp"
#include "tracking/local_mapper.hpp"
#include "tracking/object_tracker.hpp"
#include "tracking/options.hpp"

namespace twistslam::tracking {

enum class Status { kInitialized, kOk, kLost, kRelocalized };
const char* to_string(Status status);

struct TrackResult {
  Status status = Status::kLost;
  Mat4 T_w_c = Mat4::Identity();
  bool is_keyframe = false;
  int num_inliers = 0;
  int num_map_points = 0;
  int num_keyframes = 0;
  int num_lidar_depth = 0;  // keypoints that took their depth from the scan
  ObjectTrackingReport objects;  // visual object tracking of this frame
  std::vector<std::pair<std::string, double>> timings_ms;  // stage -> ms, in pipeline order
};

// Pose of every tracked frame, re-expressed through its reference keyframe so that bundle
// adjustment corrections reach the frames between keyframes.
struct TrajectoryEntry {
  int frame_index;
  double timestamp;
  int reference_keyframe;  // -1: no keyframe yet (pose kept as tracked)
  Mat4 T_c_r;              // frame pose relative to the reference keyframe (or T_c_w)
  Status status;
};

class System {
 public:
  System(const geometry::StereoCamera& camera, const SlamOptions& options);

  // left / right: CV_8UC1 or CV_8UC3 (RGB, as numpy images are) of the camera's size;
  // labels: empty or CV_32SC1 class ids per pixel; points_c: the frame's LiDAR scan (N x 3,
  // frame c; empty: none), used for keypoint depth when options.lidar.use_depth;
  // instances: empty or CV_32SC1 panoptic instance ids (0: none) and flow: empty or CV_32FC2
  // optical flow from the previous frame, both for visual object tracking; detections: the
  // frame's 3D boxes (camera frame) for the LiDAR fusion of the object tracking.
  // Throws std::invalid_argument on bad sizes.
  TrackResult track(int index, double timestamp, const cv::Mat& left, const cv::Mat& right,
                    const cv::Mat& labels = cv::Mat(), const Points3& points_c = Points3(),
                    const cv::Mat& instances = cv::Mat(), const cv::Mat& flow = cv::Mat(),
                    const std::vector<objects::Detection>& detections = {});

  // The accessors below first apply a local BA still solving in its thread
  // (local_ba.asynchronous), so they always see the state after the last frame's BA.
  // T_w_c of every frame tracked so far, refined through the keyframes.
  std::vector<std::pair<TrajectoryEntry, Mat4>> trajectory();
  const map::Map& map();
  const ObjectTracker& objects();
  // Applies the pending local BA (LocalMapper::finish_bundle_adjustment) and what the
  // synchronous BA would have refined at once: the last frame's pose, the keyframe frame's
  // trajectory entry. Nothing when none is pending; the accessors and track() call it.
  void finish_local_ba();
  // The object tracks' final smoothing against the refined trajectory (ObjectTracker::
  // smooth_tracks): once the sequence ends; tracking more frames afterwards is allowed, but
  // a smoothed track is never smoothed again.
  ObjectSmoothingReport smooth_objects();
  const objects::RoadPlaneEstimator& road_plane() const { return road_plane_; }  // no BA input
  const SlamOptions& options() const { return options_; }
  void reset();

 private:
  // The frame's pose relative to the reference keyframe (BA corrections reach it later).
  void record_trajectory(const Frame& frame, Status status);
  FinishedBundleAdjustment finished_ba_;  // applied since the last track(): reported by the next

  SlamOptions options_;
  geometry::StereoCamera camera_;
  FrameBuilder frame_builder_;
  CameraTracker camera_tracker_;
  LocalMapper local_mapper_;
  ObjectTracker object_tracker_;
  map::Map map_;

  enum class State { kEmpty, kTracking, kLost } state_ = State::kEmpty;
  // The keyframe sharing most points with the last frame (or the newest keyframe): the
  // trajectory stores poses relative to it, and it is the keyframe decision's reference.
  int reference_keyframe_ = -1;
  std::vector<TrajectoryEntry> trajectory_;
  Mat4 pending_keyframe_T_c_w_ = Mat4::Identity();  // tracked pose of the keyframe being adjusted
  int frames_since_ba_start_ = 0;  // frames tracked while it was pending (apply_delay_frames)
  // Road points of each keyframe (stereo keypoints labelled road_class_id, and with
  // visual_objects.road_lidar_points the scan's returns on road pixels away from the mask's
  // boundary, tracking/road_lidar_points.hpp) -> the road plane, whose normal is the planar
  // link's (TwistSLAM: the road cluster's plane). Until a fit is accepted it is "up" of the
  // first camera (y down).
  void add_road_points(const Frame& frame, const cv::Mat& labels, const Points3& points_c);
  objects::RoadPlaneEstimator road_plane_;
  Vec3 road_up_w_ = Vec3(0, -1, 0);
};

}  // namespace twistslam::tracking
