#pragma once
// Oriented 3D boxes in the camera frame c (KITTI convention: yaw = rotation_y about the
// camera y axis, which points down; the box's length runs along its own x axis).
#include <array>

#include "geometry/types.hpp"

namespace twistslam::geometry {

struct Box3D {
  Vec3 center = Vec3::Zero();  // geometric centre (KITTI labels give the bottom centre)
  double length = 0, width = 0, height = 0;  // m, along object x, z, y
  double yaw = 0;                            // rad, KITTI rotation_y

  // From a numpy row [cx, cy, cz, l, w, h, ry].
  static Box3D from_row(const double* row);
  // Pose T_c_o of the box frame (origin at the centre, x along length, y down).
  Mat4 pose() const;
  // Corners in frame c: 0-3 bottom face (y = cy + h/2), 4-7 top face, counter-clockwise
  // seen from above starting at (+l/2, +w/2).
  std::array<Vec3, 8> corners() const;
  // Bottom-face corners as (x, z) pairs: the bird-view rectangle.
  std::array<Vec2, 4> bev_corners() const;
  double volume() const { return length * width * height; }
  bool valid() const;  // finite, positive size
};

// Image bounding box [x1, y1, x2, y2] of a box's projection through P (3x4). Edges that cross
// the near plane z = z_near are cut there so boxes partly behind the camera still project.
// All corners behind: NaNs. Clipped to [0, width-1] x [0, height-1] when both are > 0.
Vec4 project_box(const Box3D& box, const Mat34& P, int width = 0, int height = 0,
                 double z_near = 0.1);

}  // namespace twistslam::geometry
