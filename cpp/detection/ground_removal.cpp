#include "detection/ground_removal.hpp"

#include <algorithm>
#include <cmath>

namespace twistslam::detection {

namespace {
constexpr float kUnknown = std::numeric_limits<float>::infinity();

// One chamfer sweep of the lower envelope: each cell takes the smaller of its height and a
// visited neighbour's plus the slope cost of the step. `forward` visits rows and columns in
// increasing order (neighbours above / left), else in decreasing order.
void envelope_sweep(GroundGrid& g, float step_cost, float diagonal_cost, bool forward) {
  const int rows = g.rows, cols = g.cols, d = forward ? -1 : 1;
  for (int k = 0; k < rows; ++k) {
    const int r = forward ? k : rows - 1 - k;
    for (int m = 0; m < cols; ++m) {
      const int c = forward ? m : cols - 1 - m;
      float best = g.road_up[r * cols + c];
      const int rn = r + d, cn = c + d;
      if (cn >= 0 && cn < cols) best = std::min(best, g.road_up[r * cols + cn] + step_cost);
      if (rn >= 0 && rn < rows) {
        best = std::min(best, g.road_up[rn * cols + c] + step_cost);
        if (c - 1 >= 0) best = std::min(best, g.road_up[rn * cols + c - 1] + diagonal_cost);
        if (c + 1 < cols) best = std::min(best, g.road_up[rn * cols + c + 1] + diagonal_cost);
      }
      g.road_up[r * cols + c] = best;
    }
  }
}
}  // namespace

float GroundGrid::road_at(double x, double z) const {
  const int c = static_cast<int>(std::floor((x - x0) / cell_m));
  const int r = static_cast<int>(std::floor((z - z0) / cell_m));
  if (c < 0 || c >= cols || r < 0 || r >= rows) return kUnknown;
  return road_up[static_cast<std::size_t>(r) * cols + c];
}

GroundGrid estimate_ground(const std::vector<ScenePoint>& points, const DetectorOptions& o) {
  GroundGrid g;
  g.cell_m = o.ground_cell_m;
  // a square of half-side max_range_m around the sensor holds every selected point
  g.cols = g.rows = static_cast<int>(std::ceil(2.0 * o.max_range_m / g.cell_m)) + 1;
  g.x0 = g.z0 = -0.5 * g.cols * g.cell_m;
  const std::size_t cells = static_cast<std::size_t>(g.cols) * g.rows;
  const int k = o.ground_rank;
  // the k lowest heights of each cell, ascending (insertion into a k-slot list)
  std::vector<float> lowest(cells * k, kUnknown);
  std::vector<int> count(cells, 0);
  for (const ScenePoint& p : points) {
    const int c = static_cast<int>(std::floor((p.x - g.x0) / g.cell_m));
    const int r = static_cast<int>(std::floor((p.z - g.z0) / g.cell_m));
    if (c < 0 || c >= g.cols || r < 0 || r >= g.rows) continue;
    const std::size_t cell = static_cast<std::size_t>(r) * g.cols + c;
    ++count[cell];
    float* slots = &lowest[cell * k];
    if (p.up >= slots[k - 1]) continue;
    int j = k - 1;
    for (; j > 0 && slots[j - 1] > p.up; --j) slots[j] = slots[j - 1];
    slots[j] = p.up;
  }
  g.road_up.assign(cells, kUnknown);
  for (std::size_t cell = 0; cell < cells; ++cell)
    if (count[cell] >= k) g.road_up[cell] = lowest[cell * k + k - 1];
  const float step = static_cast<float>(o.max_ground_slope * g.cell_m);
  const float diagonal = static_cast<float>(o.max_ground_slope * g.cell_m * M_SQRT2);
  envelope_sweep(g, step, diagonal, true);
  envelope_sweep(g, step, diagonal, false);
  return g;
}

std::vector<float> height_above_road(const std::vector<ScenePoint>& points, const GroundGrid& grid) {
  std::vector<float> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    out[i] = points[i].up - grid.road_at(points[i].x, points[i].z);  // inf road -> -inf
  return out;
}

}  // namespace twistslam::detection
