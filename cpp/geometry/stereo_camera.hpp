#pragma once
// Rectified pinhole stereo pair built from KITTI's P2 / P3. Points live in the rectified
// reference camera frame c (docs/design.md); each colour camera sits at a small offset from it,
// so X_left = X_c + t_left, and P2 = K [I | t_left] (the fourth column is never dropped).
#include "geometry/types.hpp"

namespace twistslam::geometry {

struct StereoCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double baseline = 0;          // m, left-to-right along x (positive)
  Vec3 t_left = Vec3::Zero();   // X_left  = X_c + t_left
  Vec3 t_right = Vec3::Zero();  // X_right = X_c + t_right
  int width = 0, height = 0;    // px; 0 = unknown
  // px: what the images' disparity lacks against the calibration, fx b / Z = (u_left - u_right)
  // + disparity_offset; equivalently the right image's principal point is cx + disparity_offset.
  // 0 trusts P_left / P_right. On real KITTI colour pairs the images are ~0.6 px short of the
  // LiDAR's geometry at every range (docs/camera_scale.md), which makes stereo 2-7 % too deep;
  // it is estimated from the scans (lidar::estimate_disparity_offset) or set in the config.
  double disparity_offset = 0;

  // Throws std::invalid_argument if the pair is not rectified (different K) or degenerate.
  static StereoCamera from_kitti(const Mat34& P_left, const Mat34& P_right, int width,
                                 int height, double disparity_offset = 0);
  // Depth along the left optical axis of a measured disparity (<= 0 where d + offset <= 0).
  double depth_from_disparity(double disparity) const;

  Mat3 K() const;
  // Pixel of X_c in the left / right image; no visibility test (see in_image).
  Vec2 project(const Vec3& X_c) const;
  Vec2 project_right(const Vec3& X_c) const;
  // Point in frame c at pixel uv of the left image and depth along the left optical axis.
  Vec3 backproject(const Vec2& uv, double depth) const;
  // Point in frame c from a left pixel and its measured disparity u_left - u_right,
  // Z = fx b / (d + disparity_offset); NaN unless d + disparity_offset > 0.
  Vec3 triangulate(const Vec2& uv_left, double disparity) const;
  bool in_image(const Vec2& uv, double border = 0.0) const;
};

}  // namespace twistslam::geometry
