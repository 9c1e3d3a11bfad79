// The depth of a far camera-only vehicle track from the LiDAR (not in the paper, in the spirit
// of its LiDAR fusion). Beyond ~30 m a stereo depth is good to 1-3 m (0.3-0.5 px of a 7-13 px
// disparity), and a far car's matches lean one way for many frames (corners on a nearer
// occluder's edge, a slow drift along the line of sight that its projections barely show), while
// the 20-50 LiDAR returns on its mask measure its visible surface to centimetres. Online, each
// such row keeps those returns; at the end, once the final smoothing has placed the rows, each
// row's points are compared with the returns around them (the median of return depth over point
// depth, as the LiDAR check, object_lidar_check.cpp), the track's median of those row ratios
// scales every far row's position along its line of sight, and the scale grows in from
// far_lidar_align_min_depth_m over far_lidar_align_ramp_m so that no row jumps where it starts.
// A whole track's median, not each row's: single rows scatter by a few per cent (a point on a
// car's rear edge against returns on its roof).
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "tracking/object_lidar_align.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
using detail::median_value;
using detail::kDepthCheckMinReturns;
using detail::kDepthCheckRadiusPx;
using detail::transform;

namespace {
bool camera_only_vehicle(const objects::ObjectTrack& track) {
  if (track.canonical || track.link != geometry::LinkType::kPlanar) return false;
  return std::none_of(track.frames.begin(), track.frames.end(),
                      [](const objects::TrackFrame& r) { return r.has_detection(); });
}

// The median of the kept returns' depth around uv, by the LiDAR check's rule
// (detail::kDepthCheckRadiusPx, kDepthCheckMinReturns; NaN: too few).
double returns_depth_near(const Points3& returns, const Vec2& uv) {
  std::vector<double> depths;
  for (Eigen::Index i = 0; i < returns.rows(); ++i) {
    const double du = returns(i, 0) - uv.x(), dv = returns(i, 1) - uv.y();
    if (du * du + dv * dv <= kDepthCheckRadiusPx * kDepthCheckRadiusPx) depths.push_back(returns(i, 2));
  }
  if (static_cast<int>(depths.size()) < kDepthCheckMinReturns) return std::nan("");
  return median_value(depths);
}
}  // namespace

void ObjectTracker::keep_far_lidar_returns(const Frame& frame) {
  const ObjectLidarOptions& o = lidar_options_;
  if (o.far_lidar_align_min_depth_m <= 0 || !scan_ || instances_.empty()) return;
  // rows a little nearer online may lie beyond the bound once smoothed
  const double keep_from_m = o.far_lidar_align_min_depth_m * (1.0 - o.far_lidar_align_max_ratio);
  for (size_t c = 0; c < tracks_.size(); ++c) {
    objects::ObjectTrack& track = tracks_[c];
    const int instance = clusters_[c].instance;
    if (!track.alive() || track.frames.empty() || instance <= 0 || !camera_only_vehicle(track)) continue;
    objects::TrackFrame& row = track.last();
    if (row.frame != frame.index || !row.reported) continue;
    if ((frame.T_c_w * row.T_w_o)(2, 3) < keep_from_m) continue;
    const lidar::ScanProjection* returns = instance_returns(instance);
    if (returns == nullptr || static_cast<int>(returns->returns.size()) < o.lidar_check_min_returns) continue;
    row.far_lidar_returns.resize(static_cast<Eigen::Index>(returns->returns.size()), 3);
    Eigen::Index n = 0;
    for (const lidar::ProjectedReturn& p : returns->returns) row.far_lidar_returns.row(n++) << p.u, p.v, p.depth;
  }
}

// A camera-only cluster's origin is the median of its points, which lie on its visible faces: a
// move nearer than the face the LiDAR sees is the points' fault, not the track's. Points
// smeared behind the origin by a far track's lagging depth motion give a ratio below 1 that
// pulled the origin in front of the car (urban s26's lead car at 55-66 m: the returns on its
// rear at 56 m, the origin moved from 56.9 to 54.7 m, a ghost).
double far_surface_floor(const objects::ObjectTrack& track, const std::map<int, Mat4>& T_c_w_of_frame,
                         double min_depth_m, double quantile) {
  std::vector<double> floors;
  for (const objects::TrackFrame& row : track.frames) {
    const auto pose = T_c_w_of_frame.find(row.frame);
    if (!row.reported || row.far_lidar_returns.rows() == 0 || pose == T_c_w_of_frame.end()) continue;
    const double depth = (pose->second * row.T_w_o)(2, 3);
    if (depth < min_depth_m) continue;
    std::vector<double> returns;
    for (Eigen::Index i = 0; i < row.far_lidar_returns.rows(); ++i)
      returns.push_back(row.far_lidar_returns(i, 2));
    const auto at =
        returns.begin() + static_cast<std::ptrdiff_t>(quantile * static_cast<double>(returns.size() - 1));
    std::nth_element(returns.begin(), at, returns.end());
    floors.push_back(*at / depth);
  }
  return floors.empty() ? 0.0 : median_value(floors);
}

void ObjectTracker::align_far_rows_to_lidar(const std::map<int, Mat4>& T_c_w_of_frame) {
  const ObjectLidarOptions& o = lidar_options_;
  if (o.far_lidar_align_min_depth_m <= 0) return;
  for (size_t c = 0; c < tracks_.size(); ++c) {
    objects::ObjectTrack& track = tracks_[c];
    if (!camera_only_vehicle(track)) continue;
    const std::vector<objects::ObjectPoint>& points = clusters_[c].points;
    std::vector<double> row_ratios;
    for (const objects::TrackFrame& row : track.frames) {
      const auto pose = T_c_w_of_frame.find(row.frame);
      if (!row.reported || row.far_lidar_returns.rows() == 0 || pose == T_c_w_of_frame.end()) continue;
      const Mat4 T_c_o = pose->second * row.T_w_o;
      if (T_c_o(2, 3) < o.far_lidar_align_min_depth_m) continue;
      std::vector<double> ratios;
      for (const objects::ObjectPoint& p : points) {
        const Vec3 X_c = transform(T_c_o, p.X_o);
        if (X_c.z() <= 0.1) continue;
        const Vec2 uv = camera_.project(X_c);
        if (!camera_.in_image(uv)) continue;
        const double depth = returns_depth_near(row.far_lidar_returns, uv);
        if (std::isfinite(depth)) ratios.push_back(depth / X_c.z());
      }
      if (static_cast<int>(ratios.size()) < o.lidar_check_min_points) continue;
      const double ratio = median_value(ratios);
      if (std::abs(ratio - 1.0) <= o.far_lidar_align_max_ratio) row_ratios.push_back(ratio);
    }
    if (static_cast<int>(row_ratios.size()) < o.far_lidar_align_min_rows) continue;
    double ratio = median_value(row_ratios);
    if (ratio < 1.0 && o.far_lidar_align_surface_floor) {
      // nearer, but not past the face its returns measure, less the margin (a ratio: the margin
      // is that fraction of the origin's depth)
      const double lowest = far_surface_floor(track, T_c_w_of_frame, o.far_lidar_align_min_depth_m,
                                              o.far_lidar_align_surface_quantile) -
                            o.far_lidar_align_surface_margin;
      ratio = std::min(1.0, std::max(ratio, lowest));
    }
    for (objects::TrackFrame& row : track.frames) {
      const auto pose = T_c_w_of_frame.find(row.frame);
      if (!row.reported || pose == T_c_w_of_frame.end()) continue;
      Mat4 T_c_o = pose->second * row.T_w_o;
      const double beyond_m = T_c_o(2, 3) - o.far_lidar_align_min_depth_m;
      if (beyond_m <= 0) continue;
      const double weight = o.far_lidar_align_ramp_m > 0 ? std::min(1.0, beyond_m / o.far_lidar_align_ramp_m) : 1.0;
      T_c_o.topRightCorner<3, 1>() *= 1.0 + (ratio - 1.0) * weight;  // along the line of sight
      row.T_w_o = pose->second.inverse() * T_c_o;
    }
  }
}

}  // namespace twistslam::tracking
