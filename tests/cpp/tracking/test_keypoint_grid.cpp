// KeypointGrid: radius queries agree with a brute-force search, and positions or radii far
// outside the image (points projected from near the camera plane, an infinite search radius)
// neither crash nor reach an out-of-range float-to-int conversion (run under UBSan).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "tracking/keypoint_grid.hpp"

using namespace twistslam;
using twistslam::tracking::KeypointGrid;

namespace {

std::vector<Vec2> random_keypoints(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1242), v(0, 375);
  std::vector<Vec2> uv(n);
  for (auto& p : uv) p = Vec2(u(rng), v(rng));
  return uv;
}

std::vector<int> brute_force(const std::vector<Vec2>& uv, double u, double v, double radius) {
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(uv.size()); ++i)
    if ((uv[i] - Vec2(u, v)).norm() <= radius) out.push_back(i);
  return out;
}

std::vector<int> sorted_query(const KeypointGrid& grid, double u, double v, double radius) {
  std::vector<int> out;
  grid.query(u, v, radius, &out);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(KeypointGrid, QueriesMatchBruteForce) {
  const auto uv = random_keypoints(2000, 3);
  KeypointGrid grid;
  grid.build(uv, 1242, 375, 32);
  for (double radius : {0.0, 3.0, 15.0, 60.0, 500.0})
    for (const Vec2 c : {Vec2(600, 180), Vec2(0, 0), Vec2(1241, 374), Vec2(-20, 400)})
      EXPECT_EQ(sorted_query(grid, c.x(), c.y(), radius), brute_force(uv, c.x(), c.y(), radius))
          << "radius " << radius << " at " << c.transpose();
}

TEST(KeypointGrid, ExtremePositionsAndRadiiAreSafe) {
  const auto uv = random_keypoints(500, 4);
  KeypointGrid grid;
  grid.build(uv, 1242, 375, 32);
  const double inf = std::numeric_limits<double>::infinity();
  // every keypoint lies within an infinite or a huge radius
  EXPECT_EQ(sorted_query(grid, 600, 180, inf).size(), uv.size());
  EXPECT_EQ(sorted_query(grid, 600, 180, 1e30).size(), uv.size());
  // far away: nothing, whatever the cell arithmetic would give as an int
  EXPECT_TRUE(sorted_query(grid, 1e12, -1e12, 50).empty());
  EXPECT_TRUE(sorted_query(grid, 3e9, 3e9, 1e3).empty());
  // non-finite centre, NaN or negative radius: nothing
  EXPECT_TRUE(sorted_query(grid, std::nan(""), 100, 10).empty());
  EXPECT_TRUE(sorted_query(grid, 100, inf, 10).empty());
  EXPECT_TRUE(sorted_query(grid, 600, 180, std::nan("")).empty());
  EXPECT_TRUE(sorted_query(grid, 600, 180, -1).empty());
}

TEST(KeypointGrid, NonFiniteOrFarKeypointsAreStoredSafely) {
  std::vector<Vec2> uv = {Vec2(10, 10), Vec2(std::nan(""), 5), Vec2(1e15, -1e15),
                          Vec2(std::numeric_limits<double>::infinity(), 0), Vec2(20, 12)};
  KeypointGrid grid;
  grid.build(uv, 100, 50, 8);
  EXPECT_EQ(sorted_query(grid, 15, 11, 10), (std::vector<int>{0, 4}));
  EXPECT_EQ(sorted_query(grid, 1e15, -1e15, 1), (std::vector<int>{2}));  // clamped into a cell
  EXPECT_THROW(grid.build(uv, 100, 50, 0), std::invalid_argument);
}
