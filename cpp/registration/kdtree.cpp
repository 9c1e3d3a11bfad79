#include "registration/kdtree.hpp"

#include <algorithm>
#include <numeric>

namespace twistslam::registration {

namespace {
// Points per leaf: a leaf is scanned linearly, so small leaves cost tree depth and large ones
// cost distance evaluations. 8 was the fastest of {4, 8, 16, 32} for 1-NN on 500-5000 point
// car scans (benchmarks/bench_gicp.py timings).
constexpr int kLeafSize = 8;
}  // namespace

KdTree::KdTree(const std::vector<Vec3>& points) : points_(points) {
  original_index_.resize(points_.size());
  std::iota(original_index_.begin(), original_index_.end(), 0);
  if (points_.empty()) return;
  nodes_.reserve(2 * points_.size() / kLeafSize + 2);
  build(0, size());
}

int KdTree::build(int begin, int end) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(Node{});
  if (end - begin <= kLeafSize) {
    nodes_[id].first = begin;
    nodes_[id].second = end;
    return id;
  }
  // Split the widest extent at its median: balanced depth for any scan shape.
  Vec3 lo = points_[begin], hi = points_[begin];
  for (int i = begin + 1; i < end; ++i) {
    lo = lo.cwiseMin(points_[i]);
    hi = hi.cwiseMax(points_[i]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  // Sort a permutation, then apply it to points and indices together.
  std::vector<int> order(end - begin);
  std::iota(order.begin(), order.end(), begin);
  std::nth_element(order.begin(), order.begin() + (mid - begin), order.end(),
                   [&](int a, int b) { return points_[a][axis] < points_[b][axis]; });
  std::vector<Vec3> p(order.size());
  std::vector<int> idx(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    p[i] = points_[order[i]];
    idx[i] = original_index_[order[i]];
  }
  std::copy(p.begin(), p.end(), points_.begin() + begin);
  std::copy(idx.begin(), idx.end(), original_index_.begin() + begin);
  const double split = points_[mid][axis];
  const int left = build(begin, mid);
  const int right = build(mid, end);
  nodes_[id].axis = axis;
  nodes_[id].split = split;
  nodes_[id].first = left;
  nodes_[id].second = right;
  return id;
}

std::vector<Neighbor> KdTree::knn(const Vec3& query, int k) const {
  std::vector<Neighbor> out;
  knn(query, k, &out);
  return out;
}

void KdTree::knn(const Vec3& query, int k, std::vector<Neighbor>* out) const {
  out->clear();
  if (nodes_.empty() || k <= 0) return;
  out->reserve(k);
  knn_recursive(0, query, k, out);
  for (Neighbor& n : *out) n.index = original_index_[n.index];
}

// `best` is kept sorted by distance (k is small: insertion beats a heap).
void KdTree::knn_recursive(int node_id, const Vec3& q, int k, std::vector<Neighbor>* best) const {
  const Node& node = nodes_[node_id];
  if (node.axis < 0) {
    for (int i = node.first; i < node.second; ++i) {
      const double d2 = (points_[i] - q).squaredNorm();
      const int n = static_cast<int>(best->size());
      if (n == k && d2 >= best->back().squared_distance_m2) continue;
      if (n < k) best->push_back(Neighbor{});
      int j = static_cast<int>(best->size()) - 1;
      while (j > 0 && (*best)[j - 1].squared_distance_m2 > d2) {
        (*best)[j] = (*best)[j - 1];
        --j;
      }
      (*best)[j] = Neighbor{i, d2};
    }
    return;
  }
  const double diff = q[node.axis] - node.split;
  const int near_child = diff < 0.0 ? node.first : node.second;
  const int far_child = diff < 0.0 ? node.second : node.first;
  knn_recursive(near_child, q, k, best);
  if (static_cast<int>(best->size()) < k || diff * diff < best->back().squared_distance_m2)
    knn_recursive(far_child, q, k, best);
}

Neighbor KdTree::nearest(const Vec3& query, double max_squared_distance_m2) const {
  Neighbor best{-1, max_squared_distance_m2};
  if (nodes_.empty()) return best;
  nearest_recursive(0, query, &best);
  if (best.index >= 0) best.index = original_index_[best.index];
  return best;
}

void KdTree::nearest_recursive(int node_id, const Vec3& q, Neighbor* best) const {
  const Node& node = nodes_[node_id];
  if (node.axis < 0) {
    for (int i = node.first; i < node.second; ++i) {
      const double d2 = (points_[i] - q).squaredNorm();
      if (d2 < best->squared_distance_m2) *best = Neighbor{i, d2};
    }
    return;
  }
  const double diff = q[node.axis] - node.split;
  const int near_child = diff < 0.0 ? node.first : node.second;
  const int far_child = diff < 0.0 ? node.second : node.first;
  nearest_recursive(near_child, q, best);
  if (diff * diff < best->squared_distance_m2) nearest_recursive(far_child, q, best);
}

}  // namespace twistslam::registration
