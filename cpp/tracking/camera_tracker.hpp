#pragma once
// Camera tracking on static map points (paper eq. 3): the constant-velocity prediction, the
// motion-model search (or, after a loss, the last local map), the local-map search and the
// robust pose-only optimisation between them. It reads the map and updates only the points'
// tracking statistics (visible / found); keyframes and points are local mapping's.
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "tracking/frame.hpp"
#include "tracking/level_weights.hpp"
#include "tracking/options.hpp"

namespace twistslam::tracking {

struct LocalMapTracking {
  bool tracked = false;         // enough inliers after the local-map search
  int reference_keyframe = -1;  // the keyframe seeing most of the matched points (-1: none)
};

class CameraTracker {
 public:
  CameraTracker(const geometry::StereoCamera& camera, const TrackingOptions& options,
                std::vector<float> scale_factors, LevelWeights weights);

  // T_c_w of the next frame: the last frame moved by the last velocity (identity before the
  // first frame, the last pose until two consecutive frames were tracked).
  Mat4 predicted_pose() const;
  // Matches frame (at its predicted pose) to the last frame's points, or after a loss to the
  // last local map's, and optimises its pose; false when too few matches or inliers remain.
  bool track_motion(Frame& frame, map::Map& map, bool after_loss);
  // Matches the points of the local keyframes (those seeing the frame's matches and their
  // covisible neighbours) and re-optimises the pose on all matches.
  LocalMapTracking track_local_map(Frame& frame, map::Map& map);

  // The velocity from the last frame to this tracked one (call before the frame is refined
  // by a keyframe's bundle adjustment); without a last frame nothing changes.
  void update_velocity(const Frame& frame);
  // The frame the next motion-model search starts from.
  void set_last_frame(Frame frame);
  // The last frame's pose as a bundle adjustment refined it, when it is frame `frame_index`.
  void refine_last_frame_pose(int frame_index, const Mat4& T_c_w);
  void reset();

 private:
  // The last frame's matched, inlier map points (the motion model's search set).
  std::vector<int> last_frame_points(const map::Map& map) const;
  // Without a velocity: frame.T_c_w from descriptor matches to those points and PnP RANSAC
  // (descriptor_pose.hpp); unchanged when too few inliers.
  void predict_from_descriptors(Frame& frame, const map::Map& map) const;
  bool track_with_motion_model(Frame& frame, map::Map& map, double radius_scale);
  bool relocalize_in_local_map(Frame& frame, map::Map& map);
  int optimize_frame_pose(Frame& frame, const map::Map& map, bool drop_outliers);

  geometry::StereoCamera camera_;
  TrackingOptions options_;
  std::vector<float> scale_factors_;  // pyramid scale per level
  LevelWeights weights_;

  Frame last_frame_;
  bool has_last_ = false;
  Mat4 velocity_ = Mat4::Identity();  // T_c_w(i) * T_c_w(i-1)^-1 of the last two tracked frames
  bool has_velocity_ = false;         // false until two consecutive frames were tracked
  std::vector<int> local_keyframes_;  // of the last local-map search: relocalisation searches them
};

}  // namespace twistslam::tracking
