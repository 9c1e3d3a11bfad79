#pragma once
// The frame being tracked: its stereo keypoints, the map points matched to them, the pose.
#include <vector>

#include "map/keypoints.hpp"
#include "tracking/keypoint_grid.hpp"

namespace twistslam::tracking {

struct Frame {
  int index = -1;
  double timestamp = 0;
  map::StereoKeypoints keypoints;
  std::vector<int> point_ids;         // per keypoint: matched map point id or -1
  std::vector<std::uint8_t> outlier;  // per keypoint: rejected by the pose optimisation
  std::vector<std::uint8_t> usable;   // per keypoint: may track the camera (static class)
  KeypointGrid grid;
  Mat4 T_c_w = Mat4::Identity();

  int num_matched_inliers() const;
  void clear_matches();
};

}  // namespace twistslam::tracking
