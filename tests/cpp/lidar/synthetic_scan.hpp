#pragma once
// Synthetic LiDAR returns generated in the left image: a pixel (u, v) and the depth a scene
// gives it become a point of frame c (X_c = X_left - t_left). Scan lines are rows of returns
// every `line_step` px in v and `point_step` px in u, like the HDL-64 in the KITTI image
// (lines 4.2-6.3 px apart, ~2.2 px between returns on a line).
#include <functional>
#include <vector>

#include "common/kitti_camera.hpp"
#include "geometry/types.hpp"

namespace twistslam::test_scenes {

inline Vec3 point_c_at(const geometry::StereoCamera& cam, double u, double v, double depth) {
  return cam.backproject(Vec2(u, v), depth);  // frame c, depth along the left optical axis
}

// Rows of returns over [u0, u1] x [v0, v1]; depth_at(u, v) <= 0 means no return there. The
// lines start at v0 + line_offset so that tests can place keypoints between lines.
inline Points3 scan_lines(const geometry::StereoCamera& cam, double u0, double u1, double v0,
                          double v1, const std::function<double(double, double)>& depth_at,
                          double line_step = 5.0, double point_step = 2.2) {
  std::vector<Vec3> pts;
  for (double v = v0; v <= v1; v += line_step)
    for (double u = u0; u <= u1; u += point_step) {
      const double z = depth_at(u, v);
      if (z > 0) pts.push_back(point_c_at(cam, u, v, z));
    }
  Points3 out(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = pts[i];
  return out;
}

inline Points3 stack(const Points3& a, const Points3& b) {
  Points3 out(a.rows() + b.rows(), 3);
  out << a, b;
  return out;
}

}  // namespace twistslam::test_scenes
