#include "registration/kdtree.hpp"

#include <algorithm>
#include <numeric>

namespace twistslam::registration {

namespace {
// Points per leaf: a leaf is scanned linearly, so small leaves cost tree depth and large ones
// distance evaluations. Leaves of 4 to 32 points timed the same within noise for 20-NN and
// 1-NN on 1000-5000 point car scans (shared 2-core machine); 8 is kept.
constexpr int kLeafSize = 8;

// Reorders key[0, n) and index[0, n) together so that key[kth] is the kth smallest, none
// before it larger and none after it smaller (std::nth_element's contract). std::nth_element
// on the index array with an indirect comparator branches on every comparison, half of them
// mispredicted on scan coordinates (10 % of a scan pair in perf): here quickselect partitions
// branch-free (Lomuto with an unconditional swap) around a median of three, then splits off the
// keys equal to the pivot (so repeated coordinates cannot stall it).
void select_kth(double* key, int* index, int n, int kth) {
  int lo = 0, hi = n;
  auto partition = [&](int from, int to, double pivot, bool or_equal) {
    int split = from;
    for (int j = from; j < to; ++j) {
      const double x = key[j];
      const int xi = index[j];
      key[j] = key[split];
      index[j] = index[split];
      key[split] = x;
      index[split] = xi;
      split += or_equal ? x <= pivot : x < pivot;
    }
    return split;
  };
  while (hi - lo > 1) {
    const double a = key[lo], b = key[lo + (hi - lo) / 2], c = key[hi - 1];
    const double pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));
    const int below = partition(lo, hi, pivot, false);  // [lo, below) < pivot
    if (kth < below) {
      hi = below;
      continue;
    }
    const int equal_end = partition(below, hi, pivot, true);  // [below, equal_end) == pivot
    if (kth < equal_end) return;
    lo = equal_end;
  }
}

}  // namespace

KdTree::KdTree(const std::vector<Vec3>& points) {
  original_index_.resize(points.size());
  std::iota(original_index_.begin(), original_index_.end(), 0);
  if (points.empty()) return;
  nodes_.reserve(2 * points.size() / kLeafSize + 2);
  // Build on the index array only (no point copies per level), then lay the points out in
  // leaf order once.
  std::vector<double> keys(points.size());
  build(points, 0, static_cast<int>(points.size()), keys.data());
  points_.resize(points.size());
  slot_of_.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    points_[i] = points[original_index_[i]];
    slot_of_[original_index_[i]] = static_cast<int>(i);
  }
}

int KdTree::build(const std::vector<Vec3>& points, int begin, int end, double* keys) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(Node{});
  if (end - begin <= kLeafSize) {
    nodes_[id].first = begin;
    nodes_[id].second = end;
    return id;
  }
  // Split the widest extent at its median: balanced depth for any scan shape.
  Vec3 lo = points[original_index_[begin]], hi = lo;
  for (int i = begin + 1; i < end; ++i) {
    lo = lo.cwiseMin(points[original_index_[i]]);
    hi = hi.cwiseMax(points[original_index_[i]]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  for (int i = begin; i < end; ++i) keys[i] = points[original_index_[i]][axis];
  select_kth(keys + begin, original_index_.data() + begin, end - begin, mid - begin);
  const double split = keys[mid];
  const int left = build(points, begin, mid, keys);
  const int right = build(points, mid, end, keys);
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
  out->resize(std::min(k, size()));
  KnnState state{out->data(), static_cast<int>(out->size()), 0};
  Vec3 offset = Vec3::Zero();
  knn_recursive(0, query, 0.0, &offset, &state);
  for (Neighbor& n : *out) n.index = original_index_[n.index];
}

// The best `count` of at most `k` candidates, sorted by distance (insertion: a max-heap
// took 1.6x the CPU time for k = 20 on a 1000-point car scan). `cell_distance2` is the squared distance from q to the node's cell,
// `offset` its per-axis parts (Arya & Mount's incremental distance): prunes far better than
// the split plane alone.
void KdTree::knn_recursive(int node_id, const Vec3& q, double cell_distance2, Vec3* offset,
                           KnnState* state) const {
  const Node& node = nodes_[node_id];
  Neighbor* best = state->best;
  const int k = state->k;
  if (node.axis < 0) {
    for (int i = node.first; i < node.second; ++i) {
      const double d2 = (points_[i] - q).squaredNorm();
      if (state->count == k && d2 >= best[k - 1].squared_distance_m2) continue;
      int j = state->count < k ? state->count++ : k - 1;
      for (; j > 0 && best[j - 1].squared_distance_m2 > d2; --j) best[j] = best[j - 1];
      best[j] = Neighbor{i, d2};
    }
    return;
  }
  const double diff = q[node.axis] - node.split;
  const int near_child = diff < 0.0 ? node.first : node.second;
  const int far_child = diff < 0.0 ? node.second : node.first;
  knn_recursive(near_child, q, cell_distance2, offset, state);
  const double old_offset = (*offset)[node.axis];
  const double far_distance2 = cell_distance2 - old_offset * old_offset + diff * diff;
  if (state->count < k || far_distance2 < best[k - 1].squared_distance_m2) {
    (*offset)[node.axis] = diff;
    knn_recursive(far_child, q, far_distance2, offset, state);
    (*offset)[node.axis] = old_offset;
  }
}

Neighbor KdTree::nearest(const Vec3& query, double max_squared_distance_m2) const {
  return nearest(query, max_squared_distance_m2, -1);
}

Neighbor KdTree::nearest(const Vec3& query, double max_squared_distance_m2, int hint) const {
  Neighbor best{-1, max_squared_distance_m2};
  if (nodes_.empty()) return best;
  // A previous neighbour, still close, bounds the search from the start (exact all the same:
  // any nearer point is still found).
  if (hint >= 0 && hint < size()) {
    const int slot = slot_of_[hint];
    const double d2 = (points_[slot] - query).squaredNorm();
    if (d2 < best.squared_distance_m2) best = Neighbor{slot, d2};
  }
  Vec3 offset = Vec3::Zero();
  nearest_recursive(0, query, 0.0, &offset, &best);
  if (best.index >= 0) best.index = original_index_[best.index];
  return best;
}

void KdTree::nearest_recursive(int node_id, const Vec3& q, double cell_distance2, Vec3* offset,
                               Neighbor* best) const {
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
  nearest_recursive(near_child, q, cell_distance2, offset, best);
  const double old_offset = (*offset)[node.axis];
  const double far_distance2 = cell_distance2 - old_offset * old_offset + diff * diff;
  if (far_distance2 < best->squared_distance_m2) {
    (*offset)[node.axis] = diff;
    nearest_recursive(far_child, q, far_distance2, offset, best);
    (*offset)[node.axis] = old_offset;
  }
}

}  // namespace twistslam::registration
