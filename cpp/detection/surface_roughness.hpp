#pragma once
// How rough a cluster's surface is: the median surface variation (Pauly, Gross, Kobbelt 2002:
// lambda_min / (lambda_1 + lambda_2 + lambda_3) of the covariance of each return's k nearest
// returns) of its returns thinned to one per voxel, so that a neighbourhood spans a physical
// scale (~0.3 m for 10 neighbours at 0.1 m) whatever the range. A car's panels and glass are
// smooth there (real KITTI 0001 and object frames: 132 boxes on labelled cars, median 0.023,
// at most 0.066); foliage scatters its returns in depth (0001's kiosk behind a tree and
// shrubs 0.058-0.086, other vegetation up to 0.13; docs/detection.md "Foliage by its
// roughness").
#include <vector>

#include "detection/scene_points.hpp"

namespace twistslam::detection {

struct SurfaceRoughness {
  double median_variation = 0;  // in [0, 1/3]: 0 a plane, 1/3 isotropic scatter
  int num_points = 0;           // returns left after the voxel thinning (the sample size)
};

// Of the returns pts[members] (x, up, z), one per voxel_m cube kept. With fewer than
// num_neighbors + 1 thinned returns, num_points tells and median_variation is 0. Requires
// voxel_m > 0 and num_neighbors >= 3.
SurfaceRoughness surface_roughness(const std::vector<int>& members,
                                   const std::vector<ScenePoint>& pts, double voxel_m,
                                   int num_neighbors);

}  // namespace twistslam::detection
