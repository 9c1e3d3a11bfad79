#include <gtest/gtest.h>

#include <cmath>

#include "geometry/box3d.hpp"
#include "geometry/box_overlap.hpp"

using namespace twistslam;
using namespace twistslam::geometry;

namespace {
Box3D make_box(double x, double y, double z, double l, double w, double h, double yaw) {
  Box3D b;
  b.center = Vec3(x, y, z);
  b.length = l, b.width = w, b.height = h, b.yaw = yaw;
  return b;
}
}  // namespace

TEST(Boxes, CornersFollowKittiConvention) {
  const Box3D b = make_box(1, 2, 10, 4, 2, 1.5, 0.0);
  const auto c = b.corners();
  EXPECT_LT((c[0] - Vec3(3, 2.75, 11)).norm(), 1e-12);  // +l/2, bottom (y down), +w/2
  EXPECT_LT((c[4] - Vec3(3, 1.25, 11)).norm(), 1e-12);
  // rotation_y = pi/2: the length axis turns from +x to -z.
  const auto r = make_box(0, 0, 0, 4, 2, 1, M_PI / 2).corners();
  EXPECT_NEAR(r[0].z(), -2.0, 1e-12);
  EXPECT_NEAR(r[0].x(), 1.0, 1e-12);
}

TEST(Boxes, IouHandComputedCases) {
  const Box3D a = make_box(0, 0, 10, 4, 2, 1.5, 0.3);
  EXPECT_NEAR(iou_bev(a, a), 1.0, 1e-12);
  EXPECT_NEAR(iou_3d(a, a), 1.0, 1e-12);
  // Shift along the box's own width axis by 0.5 m: IoU = (w - 0.5) / (w + 0.5).
  Box3D s = a;
  const Vec3 width_axis(std::sin(0.3), 0, std::cos(0.3));  // object z in camera frame
  s.center += 0.5 * width_axis;
  EXPECT_NEAR(iou_bev(a, s), 1.5 / 2.5, 1e-9);
  EXPECT_NEAR(iou_3d(a, s), 1.5 / 2.5, 1e-9);
  // Vertical shift by h/3 changes only 3D IoU: (2/3) / (4/3) = 0.5.
  Box3D v = a;
  v.center.y() += 0.5;
  EXPECT_NEAR(iou_bev(a, v), 1.0, 1e-12);
  EXPECT_NEAR(iou_3d(a, v), 0.5, 1e-12);
  // 45-degree rotated square on a square: octagon area 8(sqrt2 - 1) l^2 / 4 for side l = 2.
  const Box3D sq = make_box(0, 0, 0, 2, 2, 1, 0.0), rot = make_box(0, 0, 0, 2, 2, 1, M_PI / 4);
  const double octagon = 8.0 * (std::sqrt(2.0) - 1.0);
  EXPECT_NEAR(bev_intersection_area(sq, rot), octagon, 1e-9);
  EXPECT_NEAR(iou_bev(sq, rot), octagon / (8.0 - octagon), 1e-9);
  // Far apart and degenerate boxes.
  EXPECT_EQ(iou_bev(a, make_box(50, 0, 10, 4, 2, 1.5, 0)), 0.0);
  EXPECT_EQ(iou_3d(a, make_box(0, 0, 10, 0, 2, 1.5, 0)), 0.0);
}

TEST(Boxes, Iou2d) {
  EXPECT_NEAR(iou_2d(Vec4(0, 0, 10, 10), Vec4(5, 0, 15, 10)), 50.0 / 150.0, 1e-12);
  EXPECT_EQ(iou_2d(Vec4(0, 0, 10, 10), Vec4(20, 20, 30, 30)), 0.0);
  EXPECT_EQ(iou_2d(Vec4(0, 0, -1, 10), Vec4(0, 0, 10, 10)), 0.0);
}

TEST(Boxes, ProjectionBoundsCornersAndClipsBehindCamera) {
  Mat34 P;
  P << 700, 0, 600, 0, 0, 700, 180, 0, 0, 0, 1, 0;
  const Box3D b = make_box(0, 0, 10, 4, 2, 1.6, 0.0);
  const Vec4 r = project_box(b, P);
  EXPECT_NEAR(r[0], 600 - 700 * 2.0 / 9.0, 1e-9);  // left edge: nearest corner x = -2 at z = 9
  EXPECT_NEAR(r[3], 180 + 700 * 0.8 / 9.0, 1e-9);
  // Straddling the camera: finite, and the clipped image box stays inside the image.
  const Vec4 c = project_box(make_box(0, 0, 0.5, 4, 2, 1.6, 0.3), P, 1242, 375);
  EXPECT_TRUE(c.allFinite());
  EXPECT_GE(c[0], 0.0);
  EXPECT_LE(c[2], 1241.0);
  EXPECT_TRUE(std::isnan(project_box(make_box(0, 0, -10, 4, 2, 1.6, 0), P)[0]));
}
