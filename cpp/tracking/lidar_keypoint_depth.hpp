#pragma once
// LiDAR depth for the keypoints of a tracked frame (beyond the paper, in its spirit: LIMO /
// DEMO / V-LOAM use the scan's metric depth for the camera). Keypoints near LiDAR returns take
// the depth of a local plane through them (cpp/lidar) instead of the stereo one, and a
// virtual right-image column consistent with the camera model, so tracking, map point
// creation and the BA's stereo residual use it unchanged; keypoints without a return keep
// their stereo depth. Returns on a-priori dynamic classes are never used (eq. 3).
#include <cstdint>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"
#include "lidar/lidar_depth_options.hpp"
#include "map/keypoints.hpp"

namespace twistslam::tracking {

struct LidarOptions {
  // Use a frame's scan, when one is given, for keypoint depth. On real KITTI 0001 (offset
  // applied in both) ATE 0.041 -> 0.037 m, RPE_R 0.0261 -> 0.0258 deg/frame
  // (docs/camera_scale.md).
  bool use_depth = true;
  lidar::LidarDepthOptions depth;
};

struct LidarDepthStats {
  int num_returns_in_image = 0;  // returns projected into the image (after the mask)
  int num_replaced = 0;          // keypoints whose stereo depth the LiDAR depth replaced
  int num_added = 0;             // keypoints without a stereo match that gained a depth
};

// The "lidar" section of the options (ranges as lidar::validate checks them), visited as
// visit("key", field, lo, hi) like the other sections (tracking/options.hpp).
template <typename Visit>
void for_each_option(LidarOptions& o, Visit&& visit) {
  visit("use_depth", o.use_depth, 0, 1);
  visit("cell_size_px", o.depth.cell_size_px, 1.0, 1024.0);
  visit("search_radius_px", o.depth.search_radius_px, 0.5, 64.0);
  visit("min_depth_m", o.depth.min_depth_m, 0.01, 1000.0);
  visit("max_depth_m", o.depth.max_depth_m, 0.1, 10000.0);
  visit("min_returns", o.depth.min_returns, 3, 10000);
  visit("max_fit_residual", o.depth.max_fit_residual, 1e-6, 10.0);
  visit("layer_gap", o.depth.layer_gap, 1e-6, 100.0);
}

// Replaces k.depth / k.u_right where the scan gives a depth. points_c: N x 3 in the
// rectified reference frame c; static_mask: empty or CV_8UC1 of the image size, 0 where a
// dynamic class is (its returns are dropped). Keypoints with usable[i] == 0 are left alone.
LidarDepthStats apply_lidar_depth(const Eigen::Ref<const Points3>& points_c,
                                  const geometry::StereoCamera& camera,
                                  const LidarOptions& options, const cv::Mat& static_mask,
                                  const std::vector<std::uint8_t>& usable,
                                  map::StereoKeypoints& k);

}  // namespace twistslam::tracking
