#pragma once
// Keypoints of one stereo frame as plain arrays (structure of arrays, one entry per keypoint
// of the left image). Shared by the tracked frame and the keyframes built from it.
#include <vector>

#include "geometry/types.hpp"
#include "map/descriptor.hpp"

namespace twistslam::map {

struct StereoKeypoints {
  std::vector<Vec2> uv;                 // px, left image, pyramid level 0
  std::vector<int> octave;              // pyramid level of detection
  std::vector<double> u_right;          // px, matched x in the right image; < 0: no stereo match
  std::vector<double> depth;            // m along the left optical axis; < 0: no stereo match
  std::vector<Descriptor> descriptors;  // ORB
  std::vector<int> label;               // semantic class id at the keypoint; -1 unknown

  size_t size() const { return uv.size(); }
  bool has_depth(size_t i) const { return depth[i] > 0; }
};

}  // namespace twistslam::map
