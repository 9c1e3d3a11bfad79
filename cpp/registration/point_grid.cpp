#include "registration/point_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace twistslam::registration {
namespace {
// m, added to a search reach when its cells are chosen: q - r and q + r are rounded, and a
// point exactly at the reach must not fall in a cell left out.
constexpr double kCoverMarginM = 1e-9;
// Growth of the reach, without a bound, when its cells held no point within it.
constexpr double kReachGrowth2 = 4.0;  // squared: the reach doubles
}  // namespace

PointGrid make_point_grid(const std::vector<Vec3>& points, double cell_m) {
  if (points.empty()) throw std::invalid_argument("make_point_grid: no points");
  if (!(cell_m > 0.0) || !std::isfinite(cell_m))
    throw std::invalid_argument("make_point_grid: the cell must be positive and finite");
  PointGrid g;
  const int n = static_cast<int>(points.size());
  Vec3 hi = points[0];
  g.origin = points[0];
  for (const Vec3& p : points) {
    g.origin = g.origin.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  double cell = cell_m;
  for (;;) {
    for (int a = 0; a < 3; ++a) g.dims[a] = static_cast<int>((hi[a] - g.origin[a]) / cell) + 1;
    if (std::int64_t{g.dims[0]} * g.dims[1] * g.dims[2] <= std::int64_t{kMaxCellsPerPoint} * n)
      break;
    cell *= 1.26;  // ~2x fewer cells per round
  }
  g.cell_m = cell;
  const int nx = g.dims[0], nxy = g.dims[0] * g.dims[1];
  std::vector<int> cell_of(n);
  g.start.assign(g.num_cells() + 1, 0);
  for (int i = 0; i < n; ++i) {
    int c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(static_cast<int>((points[i][a] - g.origin[a]) / cell), g.dims[a] - 1);
    cell_of[i] = c[0] + nx * c[1] + nxy * c[2];
    ++g.start[cell_of[i] + 1];
  }
  for (int c = 0; c < g.num_cells(); ++c) g.start[c + 1] += g.start[c];
  g.index.resize(n);
  g.points.resize(n);
  std::vector<int> fill(g.start.begin(), g.start.end() - 1);
  for (int i = 0; i < n; ++i) {
    const int s = fill[cell_of[i]]++;
    g.index[s] = i;
    g.points[s] = points[i];
  }
  return g;
}

Neighbor PointGrid::nearest(const Vec3& q, double max_d2, double bound_d2,
                            double* clearance_m) const {
  if (clearance_m != nullptr) *clearance_m = 0.0;
  if (empty()) return Neighbor{-1, max_d2};
  // Every point within the reach is seen; the nearest lies within min(max, bound). With a
  // bound, the search covers it at once: on the bench's car pairs (GICP's fallback, the bound
  // the nearest of a neighbourhood) a first try at half of it failed 82-96 % of the time and
  // scanned 10-35 % more points in all. Without one, the reach starts at a cell and doubles.
  const double last_reach2 = std::min(max_d2, bound_d2);
  double reach2 = std::isfinite(bound_d2) ? last_reach2 : std::min(last_reach2, cell_m * cell_m);
  const int nx = dims[0], nxy = dims[0] * dims[1];
  for (;;) {
    const double reach = std::sqrt(reach2) + kCoverMarginM;
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = cell_along(a, q[a] - reach);
      hi[a] = cell_along(a, q[a] + reach);
    }
    int best = -1;
    double best2 = std::numeric_limits<double>::infinity(), second2 = best2;
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y) {
        const int row = y * nx + z * nxy;
        const int end = start[row + hi[0] + 1];
        for (int j = start[row + lo[0]]; j < end; ++j) {
          const double d2 = (points[j] - q).squaredNorm();
          // branch-free: which point is nearer is unpredictable
          second2 = std::min(second2, std::max(best2, d2));
          const bool nearer = d2 < best2;
          best = nearer ? j : best;
          best2 = nearer ? d2 : best2;
        }
      }
    if (best2 <= reach2 || reach2 >= last_reach2) {
      if (clearance_m != nullptr)
        *clearance_m = std::min(std::sqrt(second2), std::sqrt(reach2));
      if (best < 0 || best2 >= max_d2) return Neighbor{-1, max_d2};
      return Neighbor{index[best], best2};
    }
    reach2 = std::min(last_reach2, kReachGrowth2 * reach2);
  }
}

}  // namespace twistslam::registration
