#include "features/orb_quadtree.hpp"

#include <algorithm>
#include <cmath>
#include <queue>

namespace twistslam::features::detail {

namespace {

// A region of the level and the range of candidate indices inside it.
struct QuadNode {
  float x0, y0, x1, y1;
  int begin, end;  // range in the index array
  int depth;
  int count() const { return end - begin; }
};

struct SplitOrder {  // priority_queue top = shallowest, then most populated
  bool operator()(const QuadNode& a, const QuadNode& b) const {
    if (a.depth != b.depth) return a.depth > b.depth;
    return a.count() < b.count();
  }
};

// The regions being built: non-empty nodes that can still be split wait in `open`, the others
// are final `leaves`.
struct QuadTree {
  const std::vector<cv::KeyPoint>& cand;
  std::vector<int> idx;  // candidate indices, each node's a contiguous range
  std::vector<QuadNode> leaves;
  std::priority_queue<QuadNode, std::vector<QuadNode>, SplitOrder> open;

  void add(const QuadNode& n) {
    if (n.count() == 0) return;
    const bool splittable = n.count() > 1 && (n.x1 - n.x0 > 1.0f || n.y1 - n.y0 > 1.0f);
    if (splittable) open.push(n); else leaves.push_back(n);
  }
  int regions() const { return static_cast<int>(open.size() + leaves.size()); }

  // Roots: about square columns over the region, so that splits give square cells.
  void add_roots(const cv::Rect2f& region) {
    const int roots = std::max(1, static_cast<int>(std::lround(region.width / region.height)));
    const float w = region.width / roots;
    int begin = 0;
    for (int r = 0; r < roots; ++r) {
      const float x0 = region.x + r * w, x1 = (r + 1 == roots) ? region.x + region.width : x0 + w;
      auto mid = std::partition(idx.begin() + begin, idx.end(),
                                [&](int i) { return cand[i].pt.x < x1 || r + 1 == roots; });
      const int end = static_cast<int>(mid - idx.begin());
      add({x0, region.y, x1, region.y + region.height, begin, end, 0});
      begin = end;
    }
  }

  // Splits the first open node into its four quadrants.
  void split_next() {
    const QuadNode n = open.top();
    open.pop();
    const float mx = 0.5f * (n.x0 + n.x1), my = 0.5f * (n.y0 + n.y1);
    auto first = idx.begin() + n.begin, last = idx.begin() + n.end;
    auto split_x = std::partition(first, last, [&](int i) { return cand[i].pt.x < mx; });
    auto split_l = std::partition(first, split_x, [&](int i) { return cand[i].pt.y < my; });
    auto split_r = std::partition(split_x, last, [&](int i) { return cand[i].pt.y < my; });
    const int a = n.begin, b = static_cast<int>(split_l - idx.begin()),
              c = static_cast<int>(split_x - idx.begin()),
              d = static_cast<int>(split_r - idx.begin()), e = n.end;
    const int depth = n.depth + 1;
    add({n.x0, n.y0, mx, my, a, b, depth});
    add({n.x0, my, mx, n.y1, b, c, depth});
    add({mx, n.y0, n.x1, my, c, d, depth});
    add({mx, my, n.x1, n.y1, d, e, depth});
  }

  // The strongest candidate of every region (open ones included).
  std::vector<int> strongest_per_region() {
    while (!open.empty()) {
      leaves.push_back(open.top());
      open.pop();
    }
    std::vector<int> keep;
    keep.reserve(leaves.size());
    for (const QuadNode& n : leaves) {
      int best = idx[n.begin];
      for (int k = n.begin + 1; k < n.end; ++k)
        if (cand[idx[k]].response > cand[best].response) best = idx[k];
      keep.push_back(best);
    }
    return keep;
  }
};

}  // namespace

std::vector<int> distribute_keypoints(const std::vector<cv::KeyPoint>& candidates,
                                      const cv::Rect2f& region, int wanted) {
  if (wanted <= 0 || candidates.empty()) return {};
  QuadTree tree{candidates, std::vector<int>(candidates.size()), {}, {}};
  for (std::size_t i = 0; i < tree.idx.size(); ++i) tree.idx[i] = static_cast<int>(i);
  tree.add_roots(region);
  while (!tree.open.empty() && tree.regions() < wanted) tree.split_next();

  std::vector<int> keep = tree.strongest_per_region();
  if (static_cast<int>(keep.size()) > wanted) {  // the last split may overshoot by up to 3
    std::nth_element(keep.begin(), keep.begin() + wanted, keep.end(), [&](int i, int j) {
      return candidates[i].response > candidates[j].response;
    });
    keep.resize(wanted);
  }
  std::sort(keep.begin(), keep.end());  // deterministic, roughly raster order
  return keep;
}

}  // namespace twistslam::features::detail
