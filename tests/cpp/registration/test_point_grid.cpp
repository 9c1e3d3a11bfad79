// The voxel grid of a scan (point_grid.hpp): every point sorted into its cell, and its nearest
// point query exact against brute force, with and without a bound, for queries inside, beside
// and far outside the scan; the clearance it reports is a true lower bound.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "registration/point_grid.hpp"

using namespace twistslam;
using namespace twistslam::registration;

namespace {

// Sheets and a blob with 1 cm noise (a car's sides and a bush), and one far outlier.
std::vector<Vec3> scene(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Vec3> points;
  for (int i = 0; i < 800; ++i) points.push_back(Vec3(4.0 * u(rng), 1.5 * u(rng), 10.0 + noise(rng)));
  for (int i = 0; i < 300; ++i) points.push_back(Vec3(noise(rng), 1.5 * u(rng), 10.0 + 1.8 * u(rng)));
  for (int i = 0; i < 100; ++i) points.push_back(Vec3(6.0 + noise(rng), 0.5 + noise(rng), 12.0 + noise(rng)));
  points.push_back(Vec3(30.0, -2.0, 40.0));
  return points;
}

Neighbor brute_nearest(const std::vector<Vec3>& points, const Vec3& q, double max_d2) {
  Neighbor best{-1, max_d2};
  for (std::size_t j = 0; j < points.size(); ++j) {
    const double d2 = (points[j] - q).squaredNorm();
    if (d2 < best.squared_distance_m2) best = Neighbor{static_cast<int>(j), d2};
  }
  return best;
}

}  // namespace

TEST(PointGrid, EveryPointLiesInItsCellAndIsKeptOnce) {
  const std::vector<Vec3> points = scene(1);
  const PointGrid grid = make_point_grid(points, 0.1);
  ASSERT_EQ(grid.points.size(), points.size());
  EXPECT_LE(grid.num_cells(), kMaxCellsPerPoint * static_cast<int>(points.size()));
  EXPECT_GT(grid.cell_m, 0.1);  // the far outlier made the grid coarser than asked
  std::vector<int> seen(points.size(), 0);
  for (int z = 0; z < grid.dims[2]; ++z)
    for (int y = 0; y < grid.dims[1]; ++y)
      for (int x = 0; x < grid.dims[0]; ++x) {
        const int c = x + grid.dims[0] * (y + grid.dims[1] * z);
        for (int s = grid.start[c]; s < grid.start[c + 1]; ++s) {
          const int i = grid.index[s];
          EXPECT_EQ(grid.points[s], points[i]);
          EXPECT_EQ(grid.cell_along(0, points[i][0]), x);
          EXPECT_EQ(grid.cell_along(1, points[i][1]), y);
          EXPECT_EQ(grid.cell_along(2, points[i][2]), z);
          ++seen[i];
        }
      }
  for (int count : seen) EXPECT_EQ(count, 1);
}

TEST(PointGrid, NearestEqualsBruteForceWithAndWithoutABound) {
  const std::vector<Vec3> points = scene(2);
  const PointGrid grid = make_point_grid(points, 0.12);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> any(0, static_cast<int>(points.size()) - 1);
  std::normal_distribution<double> offset(0.0, 1.0);
  int found = 0, none = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    // near the scan, beside it, and far outside the grid
    const double spread = trial % 3 == 0 ? 0.02 : trial % 3 == 1 ? 0.3 : 3.0;
    const Vec3 q = points[any(rng)] + spread * Vec3(offset(rng), offset(rng), offset(rng));
    const double max_d2 = trial % 2 == 0 ? 0.5 * 0.5 : std::numeric_limits<double>::infinity();
    // a bound: some point's distance (not the nearest's), or none
    const double bound2 = trial % 4 < 2 ? (points[any(rng)] - q).squaredNorm()
                                        : std::numeric_limits<double>::infinity();
    const Neighbor expected = brute_nearest(points, q, max_d2);
    double clearance = -1.0;
    const Neighbor got = grid.nearest(q, max_d2, std::max(bound2, expected.squared_distance_m2),
                                      &clearance);
    ASSERT_EQ(got.index < 0, expected.index < 0) << trial;
    if (expected.index < 0) {
      ++none;
      continue;
    }
    ++found;
    EXPECT_EQ(got.squared_distance_m2, expected.squared_distance_m2) << trial;
    EXPECT_EQ((points[got.index] - q).squaredNorm(), got.squared_distance_m2) << trial;
    double second = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < points.size(); ++j)
      if (static_cast<int>(j) != got.index) second = std::min(second, (points[j] - q).norm());
    EXPECT_GE(clearance, 0.0) << trial;
    EXPECT_LE(clearance, second) << trial;
  }
  EXPECT_GT(found, 2000);
  EXPECT_GT(none, 100);  // queries farther than 0.5 m from every point
}

TEST(PointGrid, BadInputThrowsAndAnEmptyGridFindsNothing) {
  EXPECT_THROW(make_point_grid({}, 0.1), std::invalid_argument);
  EXPECT_THROW(make_point_grid({Vec3::Zero()}, 0.0), std::invalid_argument);
  EXPECT_THROW(make_point_grid({Vec3::Zero()}, std::nan("")), std::invalid_argument);
  const PointGrid empty;
  EXPECT_EQ(empty.nearest(Vec3::Zero(), 1.0, 1.0).index, -1);
  // one point: found from anywhere within the distance, however far outside its one cell
  const PointGrid single = make_point_grid({Vec3(1.0, 2.0, 3.0)}, 0.1);
  const Neighbor n = single.nearest(Vec3(1.0, 2.0, 7.0), 25.0, std::numeric_limits<double>::infinity());
  EXPECT_EQ(n.index, 0);
  EXPECT_DOUBLE_EQ(n.squared_distance_m2, 16.0);
  EXPECT_EQ(single.nearest(Vec3(1.0, 2.0, 7.0), 16.0, 16.0).index, -1);  // exactly at the limit
}
