#include "detection/fragment_merge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twistslam::detection {

namespace {

// A cluster's bearing span in the bird's-eye view, as angles about its mean bearing (no
// wrap-around at +-pi: a car spans a few degrees).
struct BearingSpan {
  double dir_x = 0, dir_z = 1;  // unit mean bearing
  double lo = 0, hi = 0;        // rad, relative to it
};

// The bird's-eye-view bounding box of a cluster (a cheap first test of nearness).
struct Box2 {
  float x_lo = std::numeric_limits<float>::infinity(), x_hi = -x_lo;
  float z_lo = std::numeric_limits<float>::infinity(), z_hi = -z_lo;
  double distance_to(const Box2& b) const {
    const double dx = std::max({0.0f, x_lo - b.x_hi, b.x_lo - x_hi});
    const double dz = std::max({0.0f, z_lo - b.z_hi, b.z_lo - z_hi});
    return std::hypot(dx, dz);
  }
  void grow(const Box2& b) {
    x_lo = std::min(x_lo, b.x_lo), x_hi = std::max(x_hi, b.x_hi);
    z_lo = std::min(z_lo, b.z_lo), z_hi = std::max(z_hi, b.z_hi);
  }
};

double bearing_about(const BearingSpan& s, double x, double z) {
  return std::atan2(s.dir_z * x - s.dir_x * z, s.dir_x * x + s.dir_z * z);
}

BearingSpan span_of(const std::vector<int>& members, const std::vector<ScenePoint>& points) {
  BearingSpan s;
  double sx = 0, sz = 0;
  for (const int i : members) {
    const double r = std::hypot(points[i].x, points[i].z);
    if (r > 0) sx += points[i].x / r, sz += points[i].z / r;
  }
  const double n = std::hypot(sx, sz);
  if (n > 0) s.dir_x = sx / n, s.dir_z = sz / n;
  s.lo = std::numeric_limits<double>::infinity();
  s.hi = -s.lo;
  for (const int i : members) {
    const double a = bearing_about(s, points[i].x, points[i].z);
    s.lo = std::min(s.lo, a);
    s.hi = std::max(s.hi, a);
  }
  return s;
}

}  // namespace

void merge_face_fragments(const std::vector<ScenePoint>& points,
                          std::vector<std::vector<int>>* clusters, const DetectorOptions& o) {
  std::vector<std::vector<int>>& all = *clusters;
  if (o.fragment_merge_gap_m > 0.0 && all.size() > 1) {
    // fragments: clusters of little height (a bumper, a grille) beyond fragment_min_range_m,
    // lowest first; they join a cluster whose top is higher (the body behind the bumper)
    constexpr float kInf = std::numeric_limits<float>::infinity();
    std::vector<float> top(all.size(), -kInf);
    std::vector<Box2> boxes(all.size());
    std::vector<int> fragments;
    const float min_range2 = static_cast<float>(o.fragment_min_range_m * o.fragment_min_range_m);
    for (std::size_t c = 0; c < all.size(); ++c) {
      float bottom = kInf, nearest2 = kInf;
      Box2& b = boxes[c];
      for (const int i : all[c]) {
        const ScenePoint& p = points[i];
        bottom = std::min(bottom, p.up), top[c] = std::max(top[c], p.up);
        b.x_lo = std::min(b.x_lo, p.x), b.x_hi = std::max(b.x_hi, p.x);
        b.z_lo = std::min(b.z_lo, p.z), b.z_hi = std::max(b.z_hi, p.z);
        nearest2 = std::min(nearest2, p.x * p.x + p.z * p.z);
      }
      if (top[c] - bottom <= o.fragment_max_height_extent_m && nearest2 >= min_range2)
        fragments.push_back(static_cast<int>(c));
    }
    std::sort(fragments.begin(), fragments.end(), [&](int a, int b) { return top[a] < top[b]; });
    std::vector<BearingSpan> spans(all.size());
    std::vector<char> has_span(all.size(), 0), took_one(all.size(), 0);
    for (const int f : fragments) {
      if (took_one[f]) continue;  // a body keeps the fragments it took
      // the cluster behind most of the fragment's returns: for each return, a return of the
      // cluster on the same bearing (within a clustering cell at its range) and at most
      // fragment_merge_gap_m farther; the nearest such cluster on ties
      int best = -1, best_count = 0;
      double best_gap = o.fragment_merge_gap_m;
      for (std::size_t k = 0; k < all.size(); ++k) {
        if (static_cast<int>(k) == f || all[k].empty() || top[k] < top[f] + o.fragment_min_rise_m ||
            boxes[k].distance_to(boxes[f]) > o.fragment_merge_gap_m)
          continue;
        if (!has_span[k]) spans[k] = span_of(all[k], points), has_span[k] = 1;
        const double r0 = std::hypot(double{points[all[f][0]].x}, double{points[all[f][0]].z});
        const double a0 = bearing_about(spans[k], points[all[f][0]].x, points[all[f][0]].z);
        const double slack = r0 > 0 ? 4.0 * o.cluster_cell_m / r0 : M_PI;
        if (a0 < spans[k].lo - slack || a0 > spans[k].hi + slack) continue;  // quick reject
        int count = 0;
        double worst_gap = 0.0;
        for (const int i : all[f]) {
          const double xi = points[i].x, zi = points[i].z;
          const double ri = std::hypot(xi, zi);
          if (!(ri > 0)) continue;
          const double cos_cell = std::cos(o.cluster_cell_m / ri);
          double gap = std::numeric_limits<double>::infinity();
          for (const int j : all[k]) {
            const double xj = points[j].x, zj = points[j].z;
            const double rj = std::hypot(xj, zj);
            const double behind = rj - ri;
            if (behind <= 0.0 || behind >= gap) continue;
            if ((xi * xj + zi * zj) >= cos_cell * ri * rj) gap = behind;  // same bearing
          }
          if (gap <= o.fragment_merge_gap_m) ++count, worst_gap = std::max(worst_gap, gap);
        }
        if (2 * count < static_cast<int>(all[f].size())) continue;
        if (count > best_count || (count == best_count && worst_gap < best_gap))
          best = static_cast<int>(k), best_count = count, best_gap = worst_gap;
      }
      if (best < 0) continue;
      all[best].insert(all[best].end(), all[f].begin(), all[f].end());
      all[f].clear();
      took_one[best] = 1;
      boxes[best].grow(boxes[f]);
    }
  }
  all.erase(std::remove_if(all.begin(), all.end(),
                           [&](const std::vector<int>& c) {
                             return static_cast<int>(c.size()) < o.min_cluster_points;
                           }),
            all.end());
}

}  // namespace twistslam::detection
