#pragma once
// A keyframe: a tracked frame kept in the map, with its keypoints, their map points and its
// covisibility links (number of map points shared with other keyframes).
#include <map>
#include <vector>

#include "geometry/se3.hpp"
#include "map/keypoints.hpp"

namespace twistslam::map {

struct KeyFrame {
  int id = -1;
  int frame_index = -1;  // index of the sequence frame it was made from
  double timestamp = 0;
  Mat4 T_c_w = Mat4::Identity();
  StereoKeypoints keypoints;
  std::vector<int> point_ids;      // per keypoint: map point id or -1
  std::map<int, int> covisibility;  // other keyframe id -> shared map points
  int segment = 0;                  // map segment (a new one starts after tracking loss)

  Mat4 T_w_c() const { return geometry::se3_inverse(T_c_w); }
  Vec3 center_w() const { return T_w_c().topRightCorner<3, 1>(); }
  int num_tracked_points() const;
};

}  // namespace twistslam::map
