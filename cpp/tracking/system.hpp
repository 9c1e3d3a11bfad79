#pragma once
// The stereo SLAM system, one call per frame: features and stereo, camera tracking on
// static points (paper eq. 3), keyframe decision, local mapping with bundle adjustment.
// Tracking loss never throws: the frame is flagged lost, the pose is predicted with the
// constant-velocity model, and a new map segment starts from the next good stereo frame.
#include <opencv2/core/mat.hpp>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "features/orb.hpp"
#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "tracking/frame.hpp"
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
  // frame c; empty: none), used for keypoint depth when options.lidar.use_depth.
  // Throws std::invalid_argument on bad sizes.
  TrackResult track(int index, double timestamp, const cv::Mat& left, const cv::Mat& right,
                    const cv::Mat& labels = cv::Mat(), const Points3& points_c = Points3());

  // T_w_c of every frame tracked so far, refined through the keyframes.
  std::vector<std::pair<TrajectoryEntry, Mat4>> trajectory() const;
  const map::Map& map() const { return map_; }
  const SlamOptions& options() const { return options_; }
  void reset();

 private:
  Frame build_frame(int index, double timestamp, const cv::Mat& left, const cv::Mat& right,
                    const cv::Mat& labels, const Points3& points_c, TrackResult* result);
  Mat4 predicted_pose() const;
  // camera_tracking.cpp
  bool track_with_motion_model(Frame& frame, double radius_scale);
  bool track_local_map(Frame& frame);
  bool relocalize_in_local_map(Frame& frame);
  int optimize_frame_pose(Frame& frame, bool drop_outliers);
  // local_mapping.cpp
  int count_initial_points(const Frame& frame) const;
  void start_segment(Frame& frame);
  bool need_keyframe(const Frame& frame) const;
  int insert_keyframe(Frame& frame);
  int create_stereo_points(Frame& frame, int keyframe_id);
  void cull_recent_points(int keyframe_id);
  void local_bundle_adjustment(int keyframe_id);
  void bound_map_size();

  geometry::StereoCamera camera_;
  SlamOptions options_;
  features::OrbExtractor extractor_;
  std::vector<double> inv_level_sigma2_;
  std::unordered_set<int> dynamic_classes_;
  map::Map map_;

  enum class State { kEmpty, kTracking, kLost } state_ = State::kEmpty;
  Frame last_frame_;
  bool has_last_ = false;
  Mat4 velocity_ = Mat4::Identity();  // T_c_w(i) * T_c_w(i-1)^-1 of the last two tracked frames
  bool has_velocity_ = false;         // false until two consecutive frames were tracked
  int reference_keyframe_ = -1;
  int last_keyframe_frame_ = -1;
  int segment_ = -1;
  int segment_first_keyframe_ = -1;
  std::vector<int> recent_points_;
  std::vector<int> local_keyframes_;
  std::vector<TrajectoryEntry> trajectory_;
  double last_ba_ms_ = 0;  // wall time of the local BA of the last inserted keyframe
  int lidar_depth_keypoints_ = 0;  // keypoints with a LiDAR depth in the frame being built
};

}  // namespace twistslam::tracking
