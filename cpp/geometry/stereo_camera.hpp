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

  // Throws std::invalid_argument if the pair is not rectified (different K) or degenerate.
  static StereoCamera from_kitti(const Mat34& P_left, const Mat34& P_right, int width,
                                 int height);

  Mat3 K() const;
  // Pixel of X_c in the left / right image; no visibility test (see in_image).
  Vec2 project(const Vec3& X_c) const;
  Vec2 project_right(const Vec3& X_c) const;
  // Point in frame c at pixel uv of the left image and depth along the left optical axis.
  Vec3 backproject(const Vec2& uv, double depth) const;
  // Point in frame c from a left pixel and its disparity u_left - u_right (> 0), Z = fx b / d.
  Vec3 triangulate(const Vec2& uv_left, double disparity) const;
  bool in_image(const Vec2& uv, double border = 0.0) const;
};

}  // namespace twistslam::geometry
