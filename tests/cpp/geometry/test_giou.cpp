// convex_hull and the generalized IoU (giou_bev, giou_3d) of box_overlap.hpp: known hulls,
// GIoU = IoU when the enclosing hull is the union, hand-computed values, ranges, symmetry,
// monotonic decrease with distance for disjoint boxes, degenerate boxes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

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

// The hull has exactly the expected vertices (any starting point) and is counter-clockwise.
void expect_hull(const std::vector<Vec2>& points, std::vector<Vec2> expected) {
  const auto hull = convex_hull(points);
  ASSERT_EQ(hull.size(), expected.size());
  EXPECT_GT(polygon_signed_area(hull), 0.0);
  for (const auto& v : expected) {
    const bool found = std::any_of(hull.begin(), hull.end(), [&](const Vec2& h) { return (h - v).norm() < 1e-12; });
    EXPECT_TRUE(found) << "missing hull vertex " << v.transpose();
  }
  // Every input point is inside or on the hull (left of every CCW edge).
  for (const auto& p : points) {
    for (size_t i = 0; i < hull.size(); ++i) {
      const Vec2 e = hull[(i + 1) % hull.size()] - hull[i], d = p - hull[i];
      EXPECT_GE(e.x() * d.y() - e.y() * d.x(), -1e-12) << p.transpose();
    }
  }
}

}  // namespace

TEST(ConvexHull, KnownPointSets) {
  // A square with an interior point, edge mid-points (collinear) and a repeated corner.
  expect_hull({{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 1}, {1, 0}, {2, 1}, {0, 1}, {2, 2}},
              {{0, 0}, {2, 0}, {2, 2}, {0, 2}});
  expect_hull({{0, 0}, {4, 0}, {1, 3}, {1, 1}, {2, 1}}, {{0, 0}, {4, 0}, {1, 3}});
  // Clockwise input: the output is still counter-clockwise.
  expect_hull({{0, 0}, {0, 1}, {1, 1}, {1, 0}}, {{0, 0}, {1, 0}, {1, 1}, {0, 1}});
  // Two overlapping squares: a hexagon.
  expect_hull({{-1, -1}, {1, -1}, {1, 1}, {-1, 1}, {0, 0}, {2, 0}, {2, 2}, {0, 2}},
              {{-1, -1}, {1, -1}, {2, 0}, {2, 2}, {0, 2}, {-1, 1}});
  EXPECT_NEAR(polygon_signed_area(convex_hull({{-1, -1}, {1, -1}, {1, 1}, {-1, 1}, {0, 0}, {2, 0}, {2, 2}, {0, 2}})),
              8.0, 1e-12);
}

TEST(ConvexHull, DegenerateSets) {
  EXPECT_TRUE(convex_hull({}).empty());
  EXPECT_EQ(convex_hull({Vec2(1, 2)}).size(), 1u);
  // Collinear points: no area, only the two extreme points remain.
  const auto line = convex_hull({{0, 0}, {1, 1}, {3, 3}, {2, 2}});
  EXPECT_NEAR(polygon_signed_area(line), 0.0, 1e-12);
  ASSERT_EQ(line.size(), 2u);
  EXPECT_TRUE((line[0] == Vec2(0, 0) && line[1] == Vec2(3, 3)) || (line[1] == Vec2(0, 0) && line[0] == Vec2(3, 3)));
}

TEST(Giou, EqualsIouForIdenticalAndNestedBoxes) {
  const auto a = make_box(1, 1, 12, 4, 1.6, 1.5, 0.4);
  EXPECT_NEAR(giou_bev(a, a), 1.0, 1e-12);
  EXPECT_NEAR(giou_3d(a, a), 1.0, 1e-12);
  // Nested (inner box inside the outer one, also vertically): hull = outer = union.
  const auto outer = make_box(0, 1, 10, 6, 4, 3, 0.3);
  const auto inner = make_box(0.5, 1.2, 10.2, 2, 1, 1, 0.3 + 0.5);
  EXPECT_NEAR(iou_bev(outer, inner), 2.0 / 24.0, 1e-9);
  EXPECT_NEAR(giou_bev(outer, inner), iou_bev(outer, inner), 1e-9);
  EXPECT_NEAR(giou_3d(outer, inner), iou_3d(outer, inner), 1e-9);
  EXPECT_NEAR(giou_3d(outer, inner), 2.0 / 72.0, 1e-9);
  EXPECT_NEAR(giou_3d(inner, outer), 2.0 / 72.0, 1e-9);
  // Same bird view, stacked vertically with a half-height overlap: the hull in 3D is the union.
  const auto up = make_box(1, 1 - 0.75, 12, 4, 1.6, 1.5, 0.4);
  EXPECT_NEAR(giou_bev(a, up), 1.0, 1e-12);
  EXPECT_NEAR(giou_3d(a, up), iou_3d(a, up), 1e-9);
  EXPECT_NEAR(giou_3d(a, up), 1.0 / 3.0, 1e-9);
}

TEST(Giou, HandComputedAxisAlignedCases) {
  // Bird view: a = [-1, 1] x [-1, 1], b = [0, 2] x [0, 2] (x, z). Intersection 1, union 7,
  // hull = the 3 x 3 square without two corner triangles of 1/2: 8.
  const auto a = make_box(0, 0, 0, 2, 2, 2, 0.0);
  const auto b = make_box(1, 0, 1, 2, 2, 2, 0.0);
  EXPECT_NEAR(giou_bev(a, b), 1.0 / 7.0 - 1.0 / 8.0, 1e-12);
  // Same heights: 3D intersection 2, union 14, enclosing 8 x 2 = 16 (the same value).
  EXPECT_NEAR(giou_3d(a, b), 2.0 / 14.0 - (16.0 - 14.0) / 16.0, 1e-12);
  // b also one metre lower: height overlap 1, span 3; inter 1, union 15, enclosing 24.
  const auto c = make_box(1, 1, 1, 2, 2, 2, 0.0);
  EXPECT_NEAR(giou_3d(a, c), 1.0 / 15.0 - 9.0 / 24.0, 1e-12);
  EXPECT_NEAR(giou_bev(a, c), giou_bev(a, b), 1e-12);
  // Disjoint: a and d = [3, 5] x [-1, 1]: hull 6 x 2 = 12, union 8: GIoU = -1/3.
  const auto d = make_box(4, 0, 0, 2, 2, 2, 0.0);
  EXPECT_NEAR(giou_bev(a, d), -1.0 / 3.0, 1e-12);
  EXPECT_NEAR(giou_3d(a, d), -1.0 / 3.0, 1e-12);
  // Same bird view, vertically apart by a 2 m gap: 3D hull 4 x 6 = 24, union 16.
  const auto e = make_box(0, 4, 0, 2, 2, 2, 0.0);
  EXPECT_NEAR(giou_bev(a, e), 1.0, 1e-12);
  EXPECT_NEAR(giou_3d(a, e), -8.0 / 24.0, 1e-12);
}

TEST(Giou, NegativeAndDecreasingWithDistanceWhenDisjoint) {
  const auto a = make_box(0, 1, 10, 4, 1.6, 1.5, 0.2);
  for (const Vec3& dir : {Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0.6, 0, -0.8), Vec3(0, 1, 0)}) {
    double prev_bev = 2, prev_3d = 2;
    for (double s = 5.0; s < 200; s *= 1.3) {
      auto b = make_box(0, 1, 10, 3.5, 1.7, 1.4, -0.5);
      b.center += s * dir;
      const double g3 = giou_3d(a, b);
      EXPECT_LT(g3, 0.0) << s;
      EXPECT_LT(g3, prev_3d) << s << " along " << dir.transpose();
      prev_3d = g3;
      if (dir.y() == 0) {  // vertical shifts leave the bird view unchanged
        const double gb = giou_bev(a, b);
        EXPECT_LT(gb, 0.0) << s;
        EXPECT_LT(gb, prev_bev) << s << " along " << dir.transpose();
        prev_bev = gb;
      }
    }
    EXPECT_LT(prev_3d, -0.9);  // tends to -1 far away
  }
}

TEST(Giou, SymmetricBoundedAndBelowIou) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-4, 4), size(0.3, 5), yaw(-M_PI, M_PI);
  for (int trial = 0; trial < 2000; ++trial) {
    const auto a = make_box(pos(rng), 0.5 * pos(rng), pos(rng), size(rng), size(rng), size(rng), yaw(rng));
    const auto b = make_box(pos(rng), 0.5 * pos(rng), pos(rng), size(rng), size(rng), size(rng), yaw(rng));
    const double gb = giou_bev(a, b), g3 = giou_3d(a, b);
    ASSERT_TRUE(std::isfinite(gb) && std::isfinite(g3)) << trial;
    EXPECT_NEAR(gb, giou_bev(b, a), 1e-9) << trial;
    EXPECT_NEAR(g3, giou_3d(b, a), 1e-9) << trial;
    EXPECT_GE(gb, -1.0) << trial;
    EXPECT_LE(gb, 1.0 + 1e-12) << trial;
    EXPECT_GE(g3, -1.0) << trial;
    EXPECT_LE(g3, 1.0 + 1e-12) << trial;
    EXPECT_LE(gb, iou_bev(a, b) + 1e-9) << trial;
    EXPECT_LE(g3, iou_3d(a, b) + 1e-9) << trial;
  }
}

TEST(Giou, InvariantToAJointYawAboutAVerticalAxis) {
  // Turning both boxes by the same yaw about the camera's y axis changes nothing.
  const auto a = make_box(1, 1, 10, 4, 1.6, 1.5, 0.3);
  const auto b = make_box(3, 1.2, 11, 3.8, 1.5, 1.6, 1.1);
  const double phi = 0.8, c = std::cos(phi), s = std::sin(phi);
  auto turn = [&](Box3D box) {
    const Vec3 p = box.center;
    box.center = Vec3(c * p.x() + s * p.z(), p.y(), -s * p.x() + c * p.z());
    box.yaw += phi;
    return box;
  };
  EXPECT_NEAR(giou_bev(turn(a), turn(b)), giou_bev(a, b), 1e-9);
  EXPECT_NEAR(giou_3d(turn(a), turn(b)), giou_3d(a, b), 1e-9);
}

TEST(Giou, DegenerateBoxesGiveMinusOne) {
  const auto a = make_box(0, 1, 10, 4, 1.6, 1.5, 0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const auto& bad : {make_box(0, 1, 10, 0, 1.6, 1.5, 0), make_box(0, 1, 10, 4, -1, 1.5, 0),
                          make_box(0, 1, 10, 4, 1.6, 0, 0), make_box(nan, 1, 10, 4, 1.6, 1.5, 0),
                          make_box(0, 1, 10, 4, 1.6, 1.5, nan), make_box(0, 1, 10, inf, 1.6, 1.5, 0)}) {
    EXPECT_EQ(giou_bev(a, bad), -1.0);
    EXPECT_EQ(giou_bev(bad, a), -1.0);
    EXPECT_EQ(giou_3d(a, bad), -1.0);
    EXPECT_EQ(giou_3d(bad, bad), -1.0);
  }
}
