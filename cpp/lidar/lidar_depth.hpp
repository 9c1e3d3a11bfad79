#pragma once
// Metric depth of left-image keypoints from a projected LiDAR scan (docs/lidar.md):
// the returns within search_radius_px of the keypoint, a local plane fitted to them and
// evaluated on the keypoint's ray. At a depth discontinuity only the nearest layer may give a
// depth, and only to a keypoint it surrounds: background never leaks onto a foreground
// keypoint, nor foreground onto a background one.
#include <cstdint>
#include <vector>

#include "geometry/types.hpp"
#include "lidar/lidar_depth_options.hpp"
#include "lidar/scan_projection.hpp"

namespace twistslam::lidar {

enum class LidarDepthStatus : std::uint8_t {
  kPlane = 0,           // valid: all returns fit one plane
  kForeground = 1,      // valid: the near layer of a discontinuity, surrounding the keypoint
  kTooFewReturns = 2,   // fewer than min_returns within the radius (or non-finite keypoint)
  kOutsideSupport = 3,  // the returns do not surround the keypoint (e.g. above the top line)
  kDepthEdge = 4,       // near and far layers, keypoint not inside the near layer's support
  kPoorFit = 5,         // no layer split explains the returns as one plane
};

const char* to_string(LidarDepthStatus status);

struct LidarDepth {
  double depth = 0;      // m, along the left optical axis; meaningful only if valid()
  int num_returns = 0;   // returns within the radius (all layers)
  double rms_relative = 0;  // RMS relative depth residual of the accepted fit
  LidarDepthStatus status = LidarDepthStatus::kTooFewReturns;
  bool valid() const {
    return status == LidarDepthStatus::kPlane || status == LidarDepthStatus::kForeground;
  }
};

// Depth of one keypoint (pixel uv of the left image). `options` must be valid (validate();
// project_scan and the vector overload check them), the hot loop does not re-check.
LidarDepth lidar_depth_at(const Vec2& uv, const ScanProjection& scan,
                          const LidarDepthOptions& options);

// Depth of every keypoint; validates the options once.
std::vector<LidarDepth> lidar_depth_at(const std::vector<Vec2>& keypoints,
                                       const ScanProjection& scan,
                                       const LidarDepthOptions& options);

}  // namespace twistslam::lidar
