#pragma once
// A dense voxel grid over one small scan (an object scan: a few hundred to a few thousand
// points), its points sorted by cell (a counting sort). It serves the scan's k-NN
// (grid_knn.hpp) and GICP's exact nearest-neighbour fallback (gicp.hpp), where it replaces a
// KD-tree descent: the cells within a known bound of the query are scanned in flat rows.
#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/types.hpp"
#include "registration/kdtree.hpp"

namespace twistslam::registration {

struct PointGrid {
  double cell_m = 0.0;          // cell edge (m)
  Vec3 origin = Vec3::Zero();   // the lowest corner of the points' bounding box
  int dims[3] = {0, 0, 0};      // cells per axis
  std::vector<int> start;       // points of cell c: [start[c], start[c + 1]) of the next two
  std::vector<int> index;       // the caller's index of each sorted point
  std::vector<Vec3> points;     // the sorted points (copies, so a row's points are contiguous)

  bool empty() const { return points.empty(); }
  int num_cells() const { return dims[0] * dims[1] * dims[2]; }
  // The cell holding coordinate x along axis a (clamped to the grid).
  int cell_along(int a, double x) const {
    const double c = std::floor((x - origin[a]) / cell_m);
    return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(dims[a] - 1)));
  }

  // The point nearest to q within sqrt(max_d2) (index -1 when none, as KdTree::nearest: a point
  // exactly at sqrt(max_d2) is not taken), exact. `bound_d2`: a squared distance known to be
  // reached by some point (e.g. a candidate already seen; infinity when none): the search
  // starts within it. When clearance_m is given it receives a lower bound (m) on the distance
  // from q to every point of the grid other than the one returned (every other point within
  // the searched reach was measured; the rest lie beyond it).
  Neighbor nearest(const Vec3& q, double max_d2, double bound_d2,
                   double* clearance_m = nullptr) const;
};

// At most this many cells per point (a far outlier would otherwise blow the grid up); the cell
// grows instead. The bench's car scans have 0.1-3.9 cells per point (median 0.5-0.7).
inline constexpr int kMaxCellsPerPoint = 8;

// Sorts `points` (finite, non-empty) into cells of about `cell_m` (> 0; grown by 1.26 per round
// until there are at most kMaxCellsPerPoint cells per point). Throws std::invalid_argument on
// an empty point set or a cell that is not positive and finite.
PointGrid make_point_grid(const std::vector<Vec3>& points, double cell_m);

}  // namespace twistslam::registration
