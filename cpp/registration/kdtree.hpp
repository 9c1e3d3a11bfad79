#pragma once
// Static 3D KD-tree for the k nearest neighbours of object scans (a few hundred to a few
// thousand points). Built once per scan; queries are read-only and thread-safe.
#include <cstdint>
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::registration {

// One neighbour: index into the points the tree was built from, squared distance (m^2).
struct Neighbor {
  int index = -1;
  double squared_distance_m2 = 0.0;
};

class KdTree {
 public:
  KdTree() = default;
  // Copies the points (no reference to the caller's storage is kept).
  explicit KdTree(const std::vector<Vec3>& points);

  int size() const { return static_cast<int>(points_.size()); }
  // The caller's point indices in the tree's leaf order: neighbouring points come close
  // together, so querying them in this order keeps the tree's nodes in cache.
  const std::vector<int>& leaf_order() const { return original_index_; }

  // Up to k neighbours of `query`, nearest first (fewer when the tree holds fewer points).
  std::vector<Neighbor> knn(const Vec3& query, int k) const;
  // Same, written into `out` (resized to the number found) to avoid an allocation per query.
  void knn(const Vec3& query, int k, std::vector<Neighbor>* out) const;

  // The nearest point within sqrt(max_squared_distance_m2); index -1 when there is none.
  Neighbor nearest(const Vec3& query, double max_squared_distance_m2) const;
  // Same, seeded with point `hint` (e.g. the neighbour found at the previous iteration; -1 =
  // none): the result is identical, the search shorter when the hint is close.
  Neighbor nearest(const Vec3& query, double max_squared_distance_m2, int hint) const;

 private:
  // Inner node: points with coordinate `axis` below `split` go to child `first`, the others
  // to child `second`. Leaf (axis == -1): points [first, second) of the reordered arrays.
  struct Node {
    double split = 0.0;
    int axis = -1;
    int first = 0;   // inner: left child; leaf: begin
    int second = 0;  // inner: right child; leaf: end
  };
  // `keys`: scratch for the split coordinates, points.size() long.
  int build(const std::vector<Vec3>& points, int begin, int end, double* keys);
  struct KnnState {
    Neighbor* best;  // k slots, the first `count` filled, nearest first
    int k;
    int count;
  };
  void knn_recursive(int node, const Vec3& q, double cell_distance2, Vec3* offset,
                     KnnState* state) const;
  void nearest_recursive(int node, const Vec3& q, double cell_distance2, Vec3* offset,
                         Neighbor* best) const;

  std::vector<Vec3> points_;        // reordered so that each leaf is contiguous
  std::vector<int> original_index_; // points_[i] was the caller's point original_index_[i]
  std::vector<int> slot_of_;        // inverse of original_index_
  std::vector<Node> nodes_;
};

}  // namespace twistslam::registration
