#pragma once
// A 3D landmark of the map. Points of static clusters live in the world frame (paper sec.
// "Clusters creation"); dynamic clusters arrive with the object issues.
#include <map>

#include "geometry/types.hpp"
#include "map/descriptor.hpp"

namespace twistslam::map {

struct MapPoint {
  int id = -1;
  Vec3 X_w = Vec3::Zero();
  Descriptor descriptor{};         // of the observation closest to all others (re-chosen on update)
  std::map<int, int> observations;  // keyframe id -> keypoint index in that keyframe
  int cluster_id = 0;               // 0: the static cluster
  int label = -1;                   // semantic class id, -1 unknown
  int first_keyframe = -1;          // id of the keyframe that created it
  int visible = 1;                  // frames in which it was predicted inside the view
  int found = 1;                    // frames in which it was matched
  bool bad = false;

  double found_ratio() const { return visible > 0 ? static_cast<double>(found) / visible : 0.0; }
};

}  // namespace twistslam::map
