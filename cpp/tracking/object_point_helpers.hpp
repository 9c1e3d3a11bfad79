#pragma once
// Small helpers shared by the object tracker's search/update (object_tracker.cpp) and its
// cluster life cycle (object_clusters.cpp). Internal to cpp/tracking.
#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/types.hpp"
#include "objects/object_cluster.hpp"

namespace twistslam::tracking::detail {

// The point's latest observation, also appended to its bounded history (window BA) and, with
// `archive`, to its whole-life archive (final smoothing).
inline void observe(objects::ObjectPoint& p, const objects::ObjectPointObservation& o, int window,
                    bool archive) {
  p.last = o;
  if (o.u_right >= 0) ++p.stereo_seen;
  p.history.push_back(o);
  if (static_cast<int>(p.history.size()) > std::max(window, 1)) p.history.erase(p.history.begin());
  if (archive) p.archive.push_back(o);
}

// The LiDAR depth around a keypoint or point: the median of the returns on its instance's mask
// within this radius, when there are at least this many. At a mask's edge the returns lie on one
// side of a point, which a local plane refuses (no support) and a median takes; 8 px brackets a
// point by two HDL-64 lines (4.2-6.3 px apart in KITTI's image). Shared by the LiDAR check
// (instance_lidar_depth_near) and the far rows' alignment (object_lidar_align.cpp).
inline constexpr double kDepthCheckRadiusPx = 8.0;
inline constexpr int kDepthCheckMinReturns = 3;

inline Vec3 transform(const Mat4& T, const Vec3& X) {
  return T.topLeftCorner<3, 3>() * X + T.topRightCorner<3, 1>();
}

// Per-axis median of the points (robust centre: a mask bleeding onto the background gives a
// few far points that a mean would follow). points must not be empty.
inline Vec3 median_point(std::vector<Vec3> points) {
  Vec3 m;
  for (int a = 0; a < 3; ++a) {
    std::nth_element(points.begin(), points.begin() + points.size() / 2, points.end(),
                     [a](const Vec3& x, const Vec3& y) { return x[a] < y[a]; });
    m[a] = points[points.size() / 2][a];
  }
  return m;
}

// The median of values (the upper one of an even count). values must not be empty.
inline double median_value(std::vector<double> values) {
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

// The largest, over the three axes, of the spread between the points' lower and upper quantile
// (quantile and 1 - quantile, 0 <= quantile < 0.5). points must not be empty.
inline double largest_quantile_spread(const std::vector<Vec3>& points, double quantile) {
  std::vector<double> values(points.size());
  const auto lo = static_cast<std::ptrdiff_t>(quantile * static_cast<double>(points.size() - 1));
  const auto hi = static_cast<std::ptrdiff_t>(points.size() - 1) - lo;
  double largest = 0.0;
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < points.size(); ++i) values[i] = points[i][a];
    std::sort(values.begin(), values.end());
    largest = std::max(largest, values[static_cast<size_t>(hi)] - values[static_cast<size_t>(lo)]);
  }
  return largest;
}

// The scan's points (frame c) inside the box of size (l, w, h) at T_c_o, grown by margin on
// every side but the bottom, which is raised by ground_clearance; returned in frame x
// (object_scans.cpp).
Points3 points_in_box(const Points3& scan_c, const Mat4& T_c_o, const Mat4& T_x_c, const Vec3& size,
                      double margin, double ground_clearance);

// The cluster's confirmed points (found twice or more; its retired ones too with
// `with_retired`) that a re-centring takes the median of: with `prefer_stereo`, those seen in
// stereo at least once (ObjectPoint::stereo_seen) when min_points of them are, else all.
inline std::vector<Vec3> recenter_points(const objects::ObjectCluster& cluster, bool with_retired,
                                         bool prefer_stereo, int min_points) {
  const auto collect = [&](bool stereo_only) {
    std::vector<Vec3> out;
    const auto take = [&](const objects::ObjectPoint& p) {
      if (p.found >= 2 && (!stereo_only || p.stereo_seen > 0)) out.push_back(p.X_o);
    };
    for (const objects::ObjectPoint& p : cluster.points) take(p);
    if (with_retired)
      for (const objects::ObjectPoint& p : cluster.retired) take(p);
    return out;
  };
  if (prefer_stereo) {
    std::vector<Vec3> stereo = collect(true);
    if (static_cast<int>(stereo.size()) >= min_points) return stereo;
  }
  return collect(false);
}

// The fraction of the cluster's confirmed points (as recenter_points counts them, all of
// them) that were seen in stereo at least once; NaN without confirmed points.
inline double confirmed_stereo_fraction(const objects::ObjectCluster& cluster, bool with_retired) {
  int stereo = 0, all = 0;
  const auto count = [&](const objects::ObjectPoint& p) {
    if (p.found >= 2) ++all, stereo += p.stereo_seen > 0;
  };
  for (const objects::ObjectPoint& p : cluster.points) count(p);
  if (with_retired)
    for (const objects::ObjectPoint& p : cluster.retired) count(p);
  return all > 0 ? static_cast<double>(stereo) / all : std::nan("");
}

inline bool contains(const std::vector<int>& ids, int id) {
  return std::find(ids.begin(), ids.end(), id) != ids.end();
}

}  // namespace twistslam::tracking::detail
