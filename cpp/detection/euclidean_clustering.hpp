#pragma once
// Obstacle returns grouped by connected components of a bird's-eye-view occupancy grid:
// occupied cells of cluster_cell_m at most ceil(cluster_gap_m / cluster_cell_m) cells apart
// (along x and z) are one object.
// One pass over the points and one over the occupied cells: on KITTI scans this is several
// times faster than a KD-tree Euclidean clustering (PCL) of the same returns, and the height
// cap (max_object_height_m) makes the vertical axis irrelevant for road users.
#include <vector>

#include "detection/scene_points.hpp"

namespace twistslam::detection {

// Clusters as lists of positions in `points`; clusters with fewer than min_cluster_points
// returns are joined to a nearby cluster they face (fragment_merge.hpp) or dropped.
// `is_obstacle[i]` selects the returns taking part.
std::vector<std::vector<int>> cluster_bev(const std::vector<ScenePoint>& points,
                                          const std::vector<char>& is_obstacle,
                                          const DetectorOptions& options);

}  // namespace twistslam::detection
