#pragma once
// Local plane through LiDAR returns, fitted as inverse depth affine in the pixel offsets:
// a 3D plane n.X + d = 0 seen through X = z K^-1 (u, v, 1) gives 1/z = -n.K^-1 (u, v, 1) / d,
// exactly affine in (u, v). Three unknowns, linear least squares, no 3D back-projection.
#include <vector>

namespace twistslam::lidar {

struct PixelDepth {
  double du = 0, dv = 0;  // px, offset of the return from the keypoint
  double depth = 0;       // m
};

struct InverseDepthPlane {
  bool ok = false;          // false: degenerate geometry (collinear returns) or depth <= 0
  double depth = 0;         // m, the plane's depth at the keypoint (du = dv = 0)
  double rms_relative = 0;  // RMS of (z_i - z_fit) / z_fit over the returns
};

// Weighted fit of 1/z = a du + b dv + c with weights z_i, so that every residual reads as a
// relative depth error: z_i (1/z_i - 1/z_fit) = (z_fit - z_i) / z_fit. Needs >= 3 returns.
InverseDepthPlane fit_inverse_depth_plane(const std::vector<PixelDepth>& returns);

}  // namespace twistslam::lidar
