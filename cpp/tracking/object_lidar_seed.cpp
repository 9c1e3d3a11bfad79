// LiDAR depth for the keypoints of an object cluster's instance (beyond the paper, in the
// spirit of its LiDAR fusion). A car behind a nearer one shows a sliver of itself: crowded
// seed 1's car 17, 13 m ahead behind car 16, kept 15-25 keypoints on its mask but stereo depths
// for 0-3 of them (the right camera sees it hidden differently), and those often on the near
// car's edge, while ~100-400 LiDAR returns fell on its mask.
#include <cmath>
#include <limits>
#include <vector>

#include "geometry/se3.hpp"
#include "lidar/lidar_depth.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
using detail::median_value;
using detail::kDepthCheckMinReturns;
using detail::kDepthCheckRadiusPx;
using detail::transform;

namespace {
// the keypoint depth thresholds of the camera's LiDAR depth (measured on KITTI 0001)
const lidar::LidarDepthOptions kDepthOptions{};
}  // namespace

const lidar::ScanProjection* ObjectTracker::instance_returns(int instance) const {
  const std::vector<double>* depths = mask_lidar_depths(instance);  // fills mask_lidar_points_
  if (depths == nullptr || depths->empty()) return nullptr;
  auto cached = instance_returns_.find(instance);
  if (cached != instance_returns_.end()) return &cached->second;
  // only the returns on this instance's mask, near their median depth: a nearer car's edge
  // lands on the mask too (the LiDAR sits 0.27 m behind the camera; masks spill over edges),
  // and the local fit's layer rule would give a keypoint beside it that near layer
  const double median_depth = median_value(*depths);
  const double ratio = lidar_options_.mask_max_depth_ratio >= 1
                           ? lidar_options_.mask_max_depth_ratio
                           : std::numeric_limits<double>::infinity();  // 0: no depth test
  const std::vector<Vec3>& returns = mask_lidar_points_.at(instance);
  Points3 points_c(static_cast<Eigen::Index>(returns.size()), 3);
  Eigen::Index n = 0;
  for (const Vec3& p : returns)
    if (p.z() * ratio >= median_depth && p.z() <= ratio * median_depth) points_c.row(n++) = p.transpose();
  points_c.conservativeResize(n, 3);
  return &instance_returns_.emplace(instance, lidar::project_scan(points_c, camera_, kDepthOptions)).first->second;
}

double ObjectTracker::instance_lidar_depth(int instance, const Vec2& uv) const {
  const lidar::ScanProjection* scan = instance_returns(instance);
  if (scan == nullptr) return std::numeric_limits<double>::quiet_NaN();
  const lidar::LidarDepth d = lidar::lidar_depth_at(uv, *scan, kDepthOptions);
  return d.valid() ? d.depth : std::numeric_limits<double>::quiet_NaN();
}

double ObjectTracker::instance_lidar_depth_near(int instance, const Vec2& uv) const {
  const lidar::ScanProjection* scan = instance_returns(instance);
  std::vector<double> depths;
  if (scan != nullptr) {
    const double r = kDepthCheckRadiusPx;
    scan->for_each_near(uv.x(), uv.y(), r, [&](const lidar::ProjectedReturn& p) {
      if ((Vec2(p.u, p.v) - uv).squaredNorm() <= r * r) depths.push_back(p.depth);
    });
  }
  if (static_cast<int>(depths.size()) < kDepthCheckMinReturns) return std::numeric_limits<double>::quiet_NaN();
  return median_value(depths);
}

std::vector<std::pair<int, Vec3>> ObjectTracker::lidar_depth_points(const Frame& frame,
                                                                    int instance) const {
  std::vector<std::pair<int, Vec3>> out;
  if (instance_returns(instance) == nullptr) return out;
  // a far car's few returns on a small mask started it frames early from poor local planes:
  // urban s0's oncoming car 10 (oracle boxes) then flipped its heading
  if (median_value(*mask_lidar_depths(instance)) > lidar_options_.instance_lidar_max_depth_m) return out;
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  const map::StereoKeypoints& k = frame.keypoints;
  for (int i : free_mono_keypoints(frame, instance)) {
    const double depth = instance_lidar_depth(instance, k.uv[i]);
    if (std::isfinite(depth) && depth <= options_.max_depth_m)
      out.emplace_back(i, transform(T_w_c, camera_.backproject(k.uv[i], depth)));
  }
  return out;
}

}  // namespace twistslam::tracking
