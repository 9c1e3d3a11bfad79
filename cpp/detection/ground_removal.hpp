#pragma once
// Road height under every point from a grid of the scan's lowest returns, robust to slopes:
// each cell's road height is its k-th lowest return, then the grid is replaced by its
// slope-limited lower envelope  g(c) = min_n low(n) + max_slope * |c - n|  (two chamfer
// passes). Cells the road is hidden in (under a car, behind it) inherit the height of the
// visible road nearby plus at most max_slope per metre; an object's returns, all above its
// own road, never lift the road. Points more than ground_margin_m above their cell's road
// are obstacles.
#include <limits>
#include <vector>

#include "detection/scene_points.hpp"

namespace twistslam::detection {

struct GroundGrid {
  double cell_m = 1.0;       // m, side of a cell
  double x0 = 0, z0 = 0;     // m, corner of cell (0, 0)
  int cols = 0, rows = 0;    // cells along x and z
  // m, road height (up) per cell, row-major (row = z); +inf where no road was seen within
  // reach (an empty scan).
  std::vector<float> road_up;

  // Road height (up, m) at (x, z); +inf outside the grid or where unknown.
  float road_at(double x, double z) const;
};

// The road grid of `points` (see the file comment); options must be valid.
GroundGrid estimate_ground(const std::vector<ScenePoint>& points, const DetectorOptions& options);

// Height above the road (m) of every point, in the order of `points`; -inf where the road is
// unknown (no cell had ground_rank returns: such points are never obstacles).
std::vector<float> height_above_road(const std::vector<ScenePoint>& points, const GroundGrid& grid);

}  // namespace twistslam::detection
