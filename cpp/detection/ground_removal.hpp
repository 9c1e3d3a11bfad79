#pragma once
// Road height under every point, on a polar grid (azimuth segments x range bins around the
// sensor), robust to slopes and to returns below the road. The road starts at the median
// height of the lowest returns near the sensor; each segment is then walked outwards: a bin's
// k-th lowest return (among those not far below the road so far) is the road there if it
// rises at most max_ground_slope per m (+ ground_climb_m) and drops at most ground_drop_m
// (+ the slope) from the last road bin; else the bin keeps the last road height. Objects
// (higher) never lift the road; multipath returns metres below it (KITTI scans have some)
// never pull it down.
#include <vector>

#include "detection/scene_points.hpp"

namespace twistslam::detection {

struct GroundGrid {
  double bin_m = 1.0;        // m, radial length of a bin
  double segment_rad = 0.0;  // rad, angular width of a segment
  int segments = 0, bins = 0;
  // m, road height (up) per (segment, bin), row-major by segment; -inf for an empty scan
  std::vector<float> road_up;
  // cell (segment * bins + bin) of every point given to estimate_ground, -1 outside the grid
  // (kept so that the heights above the road need no second atan2 per point)
  std::vector<int> point_cell;

  // Road height (up, m) at (x, z); -inf outside the grid or for an empty scan.
  float road_at(double x, double z) const;
};

// The road grid of `points` (see the file comment); options must be valid.
GroundGrid estimate_ground(const std::vector<ScenePoint>& points, const DetectorOptions& options);

// Height above the road (m) of every point, in the order of `points` (the points `grid` was
// estimated from); +inf where the road is unknown (such points are never obstacles, being
// above max_object_height_m).
std::vector<float> height_above_road(const std::vector<ScenePoint>& points, const GroundGrid& grid);

}  // namespace twistslam::detection
