// The grid all-points k-NN (grid_knn.hpp) gives the KD-tree's k nearest neighbours of every
// point: the same sets (same distances where the order is ambiguous) and the same radius.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "registration/grid_knn.hpp"

using namespace twistslam;
using namespace twistslam::registration;

namespace {

// Checks `hood` against KdTree::knn point by point: the sorted neighbour distances agree (to
// float ranking, 1e-9 m^2), so do the index sets when the k-th distance is not tied, and the
// radius is the farthest neighbour's squared distance.
void expect_same_as_tree(const std::vector<Vec3>& points, const KdTree& tree, int k,
                         const Neighborhoods& hood) {
  ASSERT_EQ(hood.size, k);
  ASSERT_EQ(hood.indices.size(), points.size() * k);
  std::vector<Neighbor> expected;
  int mismatched_points = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    tree.knn(points[i], k, &expected);
    std::vector<int> got(hood.indices.begin() + i * k, hood.indices.begin() + (i + 1) * k);
    std::vector<double> got_d2;
    for (int j : got) got_d2.push_back((points[j] - points[i]).squaredNorm());
    std::sort(got_d2.begin(), got_d2.end());
    bool same = true;
    for (int j = 0; j < k; ++j)
      same = same && std::abs(got_d2[j] - expected[j].squared_distance_m2) < 1e-9;
    const bool tied = static_cast<int>(points.size()) > k &&
                      tree.knn(points[i], k + 1).back().squared_distance_m2 -
                              expected.back().squared_distance_m2 < 1e-9;
    if (!tied) {
      std::vector<int> want;
      for (const Neighbor& n : expected) want.push_back(n.index);
      std::sort(want.begin(), want.end());
      std::sort(got.begin(), got.end());
      same = same && got == want;
    }
    EXPECT_NEAR(hood.radius2_m2[i], expected.back().squared_distance_m2, 1e-12) << i;
    mismatched_points += !same;
  }
  EXPECT_EQ(mismatched_points, 0);
}

// A car-like scan: LiDAR rings (dense along a ring, sparse across) on a box's sides with 1 cm
// noise, at 10-20 m from the sensor, plus a few far outliers that stretch the grid.
std::vector<Vec3> ring_scan(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Vec3> points;
  for (int ring = 0; ring < 12; ++ring) {
    const double y = -0.2 + 0.11 * ring;
    for (int s = 0; s < 60; ++s) {
      const double x = -2.0 + 4.0 * s / 59.0;
      points.push_back(Vec3(5 + x + noise(rng), y + noise(rng), 14.0 + noise(rng)));
      if (s % 3 == 0) points.push_back(Vec3(3.0 + noise(rng), y, 14.0 + 0.05 * s + noise(rng)));
    }
  }
  points.push_back(Vec3(40.0, 1.0, 30.0));
  points.push_back(Vec3(-20.0, -3.0, 2.0));
  return points;
}

}  // namespace

TEST(GridKnn, EqualsTheKdTreeOnACarLikeRingScan) {
  const std::vector<Vec3> points = ring_scan(3);
  const KdTree tree(points);
  for (KnnKernel kernel : {KnnKernel::kWidest, KnnKernel::kPortable})
    for (int k : {5, 20, 30}) {
      Neighborhoods hood;
      GridKnnStats stats;
      all_knn(points, tree, k, &hood, &stats, nullptr, kernel);
      EXPECT_GT(stats.cell_size_m, 0.0);
      EXPECT_LE(stats.num_cells, 8 * static_cast<int>(points.size()));
      expect_same_as_tree(points, tree, k, hood);
    }
}

// The AVX-512 kernel (where the CPU has it) and the portable one give every point the same
// neighbour set and radius, bit for bit: only the order within a set may differ. Rows of 0 to
// 40+ candidates cover the 16-wide loop, its remainder and rows shorter than one register.
TEST(GridKnn, WideAndPortableKernelsGiveTheSameNeighbourhoods) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::vector<Vec3> points = ring_scan(9);
  for (int i = 0; i < 700; ++i) points.push_back(Vec3(u(rng), 0.3 * u(rng), u(rng)) + Vec3(5, 0, 20));
  const KdTree tree(points);
  for (int k : {4, 20, 33}) {
    Neighborhoods wide, portable;
    GridKnnStats wide_stats, portable_stats;
    all_knn(points, tree, k, &wide, &wide_stats, nullptr, KnnKernel::kWidest);
    all_knn(points, tree, k, &portable, &portable_stats, nullptr, KnnKernel::kPortable);
    EXPECT_FALSE(portable_stats.avx512);
#if defined(__x86_64__) && defined(__GNUC__)
    EXPECT_EQ(wide_stats.avx512, static_cast<bool>(__builtin_cpu_supports("avx512f")));
#endif
    EXPECT_EQ(wide_stats.num_reach_retries, portable_stats.num_reach_retries);
    EXPECT_EQ(wide.radius2_m2, portable.radius2_m2);
    int differing = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      std::vector<int> a(wide.indices.begin() + i * k, wide.indices.begin() + (i + 1) * k);
      std::vector<int> b(portable.indices.begin() + i * k, portable.indices.begin() + (i + 1) * k);
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      differing += a != b;
    }
    EXPECT_EQ(differing, 0) << "k = " << k;
  }
}

TEST(GridKnn, EqualsTheKdTreeOnRandomVolumesAndSheets) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (double thickness : {1.0, 0.05, 0.0}) {
    std::vector<Vec3> points(900);
    for (Vec3& p : points) p = Vec3(u(rng), thickness * u(rng), u(rng)) + Vec3(10, -2, 25);
    const KdTree tree(points);
    Neighborhoods hood;
    all_knn(points, tree, 20, &hood);
    expect_same_as_tree(points, tree, 20, hood);
  }
}

TEST(GridKnn, CoincidentPointsAndAllPointsAsNeighbours) {
  std::vector<Vec3> points(30, Vec3(1.0, 2.0, 3.0));  // all coincident: radius 0
  points.push_back(Vec3(1.5, 2.0, 3.0));
  const KdTree tree(points);
  Neighborhoods hood;
  all_knn(points, tree, 10, &hood);
  expect_same_as_tree(points, tree, 10, hood);
  all_knn(points, tree, static_cast<int>(points.size()), &hood);  // k = n: everyone
  expect_same_as_tree(points, tree, static_cast<int>(points.size()), hood);
  EXPECT_THROW(all_knn(points, tree, 0, &hood), std::invalid_argument);
  EXPECT_THROW(all_knn(points, tree, 32, &hood), std::invalid_argument);
}

// The k smallest candidates are selected by branch-free partitions whose first pivot is the
// previous point's k-th distance: where the density jumps (a dense cluster beside a sparse
// one, so that guess is far too small or too large) and with many equal distances (a lattice),
// the selection must still be the KD-tree's.
TEST(GridKnn, SelectionIsExactWhereTheDensityJumpsAndOnALattice) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 400; ++i) points.push_back(Vec3(u(rng), u(rng), u(rng)) * 0.2);
  for (int i = 0; i < 200; ++i) points.push_back(Vec3(u(rng), u(rng), u(rng)) * 4.0 + Vec3(0.3, 0, 0));
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 4; ++z) points.push_back(Vec3(x, y, z) * 0.1 + Vec3(-2.0, 0, 0));
  const KdTree tree(points);
  for (KnnKernel kernel : {KnnKernel::kWidest, KnnKernel::kPortable})
    for (int k : {3, 8, 20, 45}) {
      Neighborhoods hood;
      all_knn(points, tree, k, &hood, nullptr, nullptr, kernel);
      expect_same_as_tree(points, tree, k, hood);
    }
}
