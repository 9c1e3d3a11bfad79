#include "detection/euclidean_clustering.hpp"

#include "detection/fragment_merge.hpp"

#include <algorithm>
#include <cmath>

namespace twistslam::detection {

std::vector<std::vector<int>> cluster_bev(const std::vector<ScenePoint>& points,
                                          const std::vector<char>& is_obstacle,
                                          const DetectorOptions& o) {
  const double cell = o.cluster_cell_m;
  const int side = static_cast<int>(std::ceil(2.0 * o.max_range_m / cell)) + 1;
  const double origin = -0.5 * side * cell;
  // per cell: -1 empty, else the head of its list of returns (next[] chains them)
  std::vector<int> head(static_cast<std::size_t>(side) * side, -1);
  std::vector<int> next(points.size(), -1);
  std::vector<int> occupied;  // cells with at least one return, first-seen order
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!is_obstacle[i]) continue;
    const int c = static_cast<int>(std::floor((points[i].x - origin) / cell));
    const int r = static_cast<int>(std::floor((points[i].z - origin) / cell));
    if (c < 0 || c >= side || r < 0 || r >= side) continue;
    const int id = r * side + c;
    if (head[id] < 0) occupied.push_back(id);
    next[i] = head[id];
    head[id] = static_cast<int>(i);
  }
  std::vector<char> visited(head.size(), 0);
  std::vector<std::vector<int>> clusters;
  std::vector<int> stack;
  const int reach = std::max(1, static_cast<int>(std::ceil(o.cluster_gap_m / cell - 1e-9)));
  for (const int seed : occupied) {
    if (visited[seed]) continue;
    visited[seed] = 1;
    stack.assign(1, seed);
    std::vector<int> members;
    while (!stack.empty()) {
      const int id = stack.back();
      stack.pop_back();
      for (int i = head[id]; i >= 0; i = next[i]) members.push_back(i);
      const int r = id / side, c = id % side;
      for (int dr = -reach; dr <= reach; ++dr) {
        for (int dc = -reach; dc <= reach; ++dc) {
          const int rn = r + dr, cn = c + dc;
          if (rn < 0 || rn >= side || cn < 0 || cn >= side) continue;
          const int n = rn * side + cn;
          if (head[n] < 0 || visited[n]) continue;
          visited[n] = 1;
          stack.push_back(n);
        }
      }
    }
    clusters.push_back(std::move(members));
  }
  merge_face_fragments(points, &clusters, o);  // drops the fragments it does not join
  return clusters;
}

}  // namespace twistslam::detection
