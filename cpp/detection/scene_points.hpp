#pragma once
// The scan as the detector's stages see it: bird's-eye-view coordinates (x right, z forward,
// metres) and height up = -y of the rectified camera frame c, with the row of the input scan.
#include <vector>

#include "detection/detector_options.hpp"
#include "geometry/types.hpp"

namespace twistslam::detection {

struct ScenePoint {
  float x = 0, z = 0;  // m, camera x (right) and z (forward)
  float up = 0;        // m, -y: height above the camera centre
  int index = 0;       // row of the input scan
};

struct SceneSelection {
  std::vector<ScenePoint> points;  // finite, in range and (front_only) in the field of view
  int num_non_finite = 0;          // input rows with a NaN / Inf coordinate (dropped)
};

// Rows of points_c (frame c) that pass the region-of-interest options.
SceneSelection select_scene_points(const Eigen::Ref<const Points3>& points_c,
                                   const DetectorOptions& options);

}  // namespace twistslam::detection
