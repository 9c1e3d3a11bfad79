#include "detection/ground_removal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twistslam::detection {

namespace {
constexpr float kUnknown = -std::numeric_limits<float>::infinity();
// m, returns within this range of the sensor give the starting road height: at the HDL-64's
// lower beams (2.5-10 m) most of what the sensor sees around itself is road.
constexpr double kNearRoadRangeM = 10.0;

int cell_of(const GroundGrid& g, double x, double z) {
  const double r = std::sqrt(x * x + z * z);
  const int b = static_cast<int>(r / g.bin_m);
  int s = static_cast<int>((std::atan2(x, z) + M_PI) / g.segment_rad);
  if (s >= g.segments) s = g.segments - 1;  // atan2 == pi exactly
  if (b < 0 || b >= g.bins || s < 0) return -1;
  return s * g.bins + b;
}

// k-th lowest of `values` (k >= 1), or the highest if fewer
float kth_lowest(std::vector<float>& values, int k) {
  const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(k), values.size()) - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<long>(n), values.end());
  return values[n];
}
// m, how far above the road (plus ground_climb_m) the shadow line must pass for the road
// there to count as hidden: above the road's own horizon on a steady climb (within
// centimetres) and the camera centre's 0.08 m below KITTI's LiDAR; a parked car's shadow
// passes 0.3-1.4 m above the road for 80 m behind it.
constexpr double kShadowMarginM = 0.3;

}  // namespace

float GroundGrid::road_at(double x, double z) const {
  if (road_up.empty()) return kUnknown;
  const int cell = cell_of(*this, x, z);
  return cell < 0 ? kUnknown : road_up[static_cast<std::size_t>(cell)];
}

GroundGrid estimate_ground(const std::vector<ScenePoint>& points, const DetectorOptions& o) {
  GroundGrid g;
  g.bin_m = o.ground_cell_m;
  g.segments = std::max(1, static_cast<int>(std::ceil(360.0 / o.ground_segment_deg - 1e-9)));
  g.segment_rad = 2.0 * M_PI / g.segments;
  g.bins = static_cast<int>(std::ceil(o.max_range_m / g.bin_m)) + 1;
  if (points.empty()) return g;
  const std::size_t cells = static_cast<std::size_t>(g.segments) * g.bins;
  // counting sort of the heights by cell
  std::vector<int> start(cells + 1, 0);
  std::vector<int>& cell = g.point_cell;
  cell.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    cell[i] = cell_of(g, points[i].x, points[i].z);
    if (cell[i] >= 0) ++start[static_cast<std::size_t>(cell[i]) + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  std::vector<float> heights(static_cast<std::size_t>(start[cells]));
  // and each return's elevation (up / horizontal range), for the shadows of nearer returns
  std::vector<float> elevations(heights.size());
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (cell[i] < 0) continue;
    const auto slot = static_cast<std::size_t>(fill[cell[i]]++);
    heights[slot] = points[i].up;
    elevations[slot] = points[i].up / std::max(std::hypot(points[i].x, points[i].z), 1e-3f);
  }

  // starting road height: median of the bins' k-th lowest returns near the sensor
  std::vector<float> near, bin_values;
  const int near_bins = std::min(g.bins, static_cast<int>(kNearRoadRangeM / g.bin_m) + 1);
  for (int s = 0; s < g.segments; ++s) {
    for (int b = 0; b < near_bins; ++b) {
      const int c = s * g.bins + b;
      if (start[c + 1] - start[c] < o.ground_rank) continue;
      bin_values.assign(heights.begin() + start[c], heights.begin() + start[c + 1]);
      near.push_back(kth_lowest(bin_values, o.ground_rank));
    }
  }
  if (near.empty()) {  // nothing near the sensor: the lowest returns anywhere
    bin_values = heights;
    near.push_back(kth_lowest(bin_values, std::max(1, static_cast<int>(heights.size() / 20))));
  }
  const float start_up = kth_lowest(near, static_cast<int>(near.size() / 2) + 1);

  g.road_up.assign(cells, start_up);
  for (int s = 0; s < g.segments; ++s) {
    float road = start_up;
    double road_r = 0.0;  // m, range of the last bin that measured the road
    // highest elevation (up / range) of the returns of the bins walked so far: below the ray
    // at that elevation, nothing farther is seen (the camera centre stands in for the LiDAR,
    // ~0.08 m higher on KITTI)
    double horizon = -std::numeric_limits<double>::infinity();
    for (int b = 0; b < g.bins; ++b) {
      const int c = s * g.bins + b;
      const double r = (b + 0.5) * g.bin_m;
      const bool shadowed =
          o.hold_road_in_shadows && horizon * r > road + o.ground_climb_m + kShadowMarginM;
      const double rise = o.max_ground_slope * (shadowed ? g.bin_m : r - road_r);
      const float lowest_ok = static_cast<float>(road - rise - o.ground_drop_m);
      bin_values.clear();
      for (int i = start[c]; i < start[c + 1]; ++i)
        if (heights[static_cast<std::size_t>(i)] >= lowest_ok) bin_values.push_back(heights[static_cast<std::size_t>(i)]);
      // a bin a ring only grazes holds fewer than k returns: its highest then (the band
      // test above already dropped returns far below the road)
      if (!bin_values.empty()) {
        const float candidate = kth_lowest(bin_values, o.ground_rank);
        if (candidate <= road + rise + o.ground_climb_m) {
          road = candidate;
          road_r = r;
        }
      }
      g.road_up[static_cast<std::size_t>(c)] = road;
      for (int i = start[c]; i < start[c + 1]; ++i)
        horizon = std::max(horizon, static_cast<double>(elevations[static_cast<std::size_t>(i)]));
    }
  }
  return g;
}

std::vector<float> height_above_road(const std::vector<ScenePoint>& points, const GroundGrid& grid) {
  std::vector<float> out(points.size());
  const bool cached = grid.point_cell.size() == points.size() && !grid.road_up.empty();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const float road = !cached ? grid.road_at(points[i].x, points[i].z)
                       : grid.point_cell[i] < 0 ? kUnknown
                                                : grid.road_up[static_cast<std::size_t>(grid.point_cell[i])];
    out[i] = points[i].up - road;  // -inf road -> +inf
  }
  return out;
}

}  // namespace twistslam::detection
