#pragma once
// Matching map points to the keypoints of a frame by projecting them with a pose guess:
// the search of camera tracking (motion model and local map, paper sec. "Dynamic SLAM").
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "tracking/frame.hpp"

namespace twistslam::tracking {

struct ProjectionSearch {
  double radius_px = 15;   // at pyramid level 0; scaled by the keypoint's level scale
  int max_hamming = 50;    // bits
  double ratio = 0.9;      // best < ratio * second best (same pyramid level)
};

// Matches the given map points to unmatched, usable keypoints of `frame` (pose frame.T_c_w).
// `scale_factors[level]` is the pyramid scale of each level. Points projected inside the
// image get `visible` incremented when `count_visible` (local-map tracking statistics).
// Returns the number of new matches.
int search_by_projection(Frame& frame, map::Map& map, const std::vector<int>& point_ids,
                         const geometry::StereoCamera& camera,
                         const std::vector<float>& scale_factors, const ProjectionSearch& search,
                         bool count_visible = false);

}  // namespace twistslam::tracking
