#include "tracking/lidar_keypoint_depth.hpp"

#include "lidar/lidar_depth.hpp"
#include "lidar/scan_projection.hpp"

namespace twistslam::tracking {

LidarDepthStats apply_lidar_depth(const Eigen::Ref<const Points3>& points_c,
                                  const geometry::StereoCamera& camera,
                                  const LidarOptions& options, const cv::Mat& static_mask,
                                  const std::vector<std::uint8_t>& usable,
                                  map::StereoKeypoints& k) {
  LidarDepthStats stats;
  if (points_c.rows() == 0 || k.size() == 0) return stats;
  const lidar::ScanProjection scan =
      lidar::project_scan(points_c, camera, options.depth, static_mask);
  stats.num_returns_in_image = static_cast<int>(scan.returns.size());
  const std::vector<lidar::LidarDepth> depth = lidar::lidar_depth_at(k.uv, scan, options.depth);
  for (size_t i = 0; i < k.size(); ++i) {
    if (!depth[i].valid() || (i < usable.size() && !usable[i])) continue;
    // The right-image column this depth implies under the camera model (offset included):
    // the BA's stereo residual then pulls the point to the LiDAR's depth.
    const Vec3 X_c = camera.backproject(k.uv[i], depth[i].depth);
    const double u_right = camera.project_right(X_c).x();
    if (!(u_right >= 0) || !(u_right < k.uv[i].x())) continue;
    (k.has_depth(i) ? stats.num_replaced : stats.num_added) += 1;
    k.depth[i] = depth[i].depth;
    k.u_right[i] = u_right;
  }
  return stats;
}

}  // namespace twistslam::tracking
