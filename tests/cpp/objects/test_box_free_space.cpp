// Free space of a box (objects/box_free_space.hpp): a car's box holds its returns, a box in
// empty space is crossed by rays that end beyond it, and a box hidden behind an occluder has
// neither.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "objects/box_free_space.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {

// A box pose in the camera frame (x right, y down, z forward): heading along the camera's x.
Mat4 box_at(const Vec3& centre) {
  Mat4 T = Mat4::Identity();
  T.topRightCorner<3, 1>() = centre;
  return T;
}

// Returns on a vertical plane z = depth, x in [x0, x1], y in [y0, y1], every 0.1 m.
void add_plane(std::vector<Vec3>* points, double depth, double x0, double x1, double y0, double y1) {
  for (double x = x0; x <= x1 + 1e-9; x += 0.1)
    for (double y = y0; y <= y1 + 1e-9; y += 0.1) points->emplace_back(x, y, depth);
}

Points3 to_matrix(const std::vector<Vec3>& points) {
  Points3 m(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  return m;
}

const Vec3 kSize(4.5, 1.8, 1.5);  // length (along x here), width (z), height (y)

}  // namespace

TEST(BoxFreeSpace, ACarsBoxHoldsItsReturnsAndHidesTheWallBehind) {
  // the car's near face (its side: the box's length runs across the view) at 15 m, its box
  // centred 0.9 m behind it, and a wall at 30 m seen around it
  std::vector<Vec3> points;
  add_plane(&points, 15.05, -2.2, 2.2, 0.1, 1.5);  // the car's side, y down: 0.1-1.5 m below
  add_plane(&points, 30.0, -9.0, -5.0, -1.0, 1.5);  // the wall, left of the car's shadow
  add_plane(&points, 30.0, 5.0, 9.0, -1.0, 1.5);    // ... and right of it
  const BoxRayCounts c = count_box_rays(to_matrix(points), box_at(Vec3(0, 0.8, 15.9)), kSize,
                                        Vec3::Zero(), 0.3);
  EXPECT_GT(c.inside, 300);
  EXPECT_EQ(c.through, 0);
}

TEST(BoxFreeSpace, ABoxInEmptySpaceIsSeenThrough) {
  // the same scene, the box placed 4 m beyond the car's side: the wall's rays cross it
  std::vector<Vec3> points;
  add_plane(&points, 15.05, -2.2, 2.2, 0.1, 1.5);
  add_plane(&points, 30.0, -8.0, 8.0, -1.0, 1.5);  // the wall behind the box, in its full view
  const BoxRayCounts c = count_box_rays(to_matrix(points), box_at(Vec3(5.0, 0.8, 22.0)), kSize,
                                        Vec3::Zero(), 0.3);
  EXPECT_EQ(c.inside, 0);
  EXPECT_GT(c.through, 100);
}

TEST(BoxFreeSpace, AHiddenBoxHasNoVerdictAndBadRowsAreSkipped) {
  // a wall at 10 m in front of a box at 20 m: every ray ends before it
  std::vector<Vec3> points;
  add_plane(&points, 10.0, -6.0, 6.0, -1.0, 1.5);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  points.emplace_back(nan, 0.5, 30.0);
  points.emplace_back(0.0, std::numeric_limits<double>::infinity(), 30.0);
  const BoxRayCounts c = count_box_rays(to_matrix(points), box_at(Vec3(0, 0.8, 20.0)), kSize,
                                        Vec3::Zero(), 0.3);
  EXPECT_EQ(c.inside, 0);
  EXPECT_EQ(c.through, 0);
  // an empty scan, and a sensor inside the box
  EXPECT_EQ(count_box_rays(Points3(0, 3), box_at(Vec3(0, 0.8, 20.0)), kSize, Vec3::Zero(), 0.3).through, 0);
  EXPECT_EQ(count_box_rays(to_matrix(points), box_at(Vec3(0, 0, 0.5)), kSize, Vec3::Zero(), 0.3).through, 0);
}

TEST(BoxFreeSpace, TheReturnsKeptAroundABoxRetakeTheTestForABoxMovedWithinTheReach) {
  // a scene with the car's side at 15 m, a wall at 30 m and returns far off to both sides
  std::vector<Vec3> points;
  add_plane(&points, 15.05, -2.2, 2.2, 0.1, 1.5);
  add_plane(&points, 30.0, -8.0, 8.0, -1.0, 1.5);
  add_plane(&points, 12.0, -30.0, -20.0, -1.0, 1.5);
  add_plane(&points, 12.0, 20.0, 30.0, -1.0, 1.5);
  const Points3 scan = to_matrix(points);
  const Mat4 hidden_at = box_at(Vec3(5.0, 0.8, 22.0));  // the see-through box of the test above
  const Points3 kept = returns_near_box_rays(scan, hidden_at, kSize, Vec3::Zero(), 3.0);
  EXPECT_LT(kept.rows(), scan.rows() / 2);  // the returns far to the sides are left out
  // every box within the reach counts the same on the kept returns as on the whole scan:
  // moved onto the car (no longer seen through), along the ray, or sideways
  for (const Vec3& shift : {Vec3(0, 0, 0), Vec3(-2.0, 0, -1.5), Vec3(0, 0, 2.9), Vec3(2.9, 0, 0),
                            Vec3(-1.5, 0.3, 2.5)}) {
    const Mat4 moved = box_at(Vec3(5.0, 0.8, 22.0) + shift);
    const BoxRayCounts all = count_box_rays(scan, moved, kSize, Vec3::Zero(), 0.3);
    const BoxRayCounts sub = count_box_rays(kept, moved, kSize, Vec3::Zero(), 0.3);
    EXPECT_EQ(sub.inside, all.inside) << shift.transpose();
    EXPECT_EQ(sub.through, all.through) << shift.transpose();
  }
  EXPECT_EQ(returns_near_box_rays(Points3(0, 3), hidden_at, kSize, Vec3::Zero(), 3.0).rows(), 0);
}
