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
  std::vector<ScenePoint> points;  // finite, in range and (front_only) in the widened field
  int num_non_finite = 0;          // input rows with a NaN / Inf coordinate (dropped)
};

// deg, half the horizontal field the points are selected in with front_only: the field of
// view plus its margin (at most 180).
double selection_half_angle_deg(const DetectorOptions& options);

// Rows of points_c (frame c) that pass the region-of-interest options (with front_only,
// within selection_half_angle_deg of the camera axis).
SceneSelection select_scene_points(const Eigen::Ref<const Points3>& points_c,
                                   const DetectorOptions& options);

}  // namespace twistslam::detection
