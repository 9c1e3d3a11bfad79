#pragma once
// The stereo rig every C++ test scene uses: KITTI tracking sequence 0000's cameras 2 and 3
// (training/calib/0000.txt), images 1242 x 375.
#include "geometry/stereo_camera.hpp"

namespace twistslam::test_scenes {

inline geometry::StereoCamera kitti_camera() {
  Mat34 P2, P3;
  P2 << 721.5377, 0, 609.5593, 44.85728, 0, 721.5377, 172.854, 0.2163791, 0, 0, 1, 0.002745884;
  P3 << 721.5377, 0, 609.5593, -339.5242, 0, 721.5377, 172.854, 2.199936, 0, 0, 1, 0.002729905;
  return geometry::StereoCamera::from_kitti(P2, P3, 1242, 375);
}

}  // namespace twistslam::test_scenes
