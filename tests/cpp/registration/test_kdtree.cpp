// KD-tree: k nearest neighbours and the radius-bounded nearest equal a brute-force search.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "registration/kdtree.hpp"

using namespace twistslam;
using registration::KdTree;
using registration::Neighbor;

namespace {

std::vector<Vec3> random_points(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<Vec3> p(n);
  for (Vec3& x : p) x = Vec3(u(rng), 0.3 * u(rng), u(rng));  // flat, like a car scan
  return p;
}

std::vector<double> brute_force_distances(const std::vector<Vec3>& p, const Vec3& q, int k) {
  std::vector<double> d;
  for (const Vec3& x : p) d.push_back((x - q).squaredNorm());
  std::sort(d.begin(), d.end());
  d.resize(std::min<std::size_t>(k, d.size()));
  return d;
}

}  // namespace

TEST(KdTree, KnnEqualsBruteForce) {
  const std::vector<Vec3> points = random_points(1500, 1);
  const KdTree tree(points);
  const std::vector<Vec3> queries = random_points(200, 2);
  for (int k : {1, 5, 20}) {
    for (const Vec3& q : queries) {
      const std::vector<Neighbor> found = tree.knn(q, k);
      const std::vector<double> expected = brute_force_distances(points, q, k);
      ASSERT_EQ(found.size(), expected.size());
      for (std::size_t i = 0; i < found.size(); ++i) {
        EXPECT_DOUBLE_EQ(found[i].squared_distance_m2, expected[i]);
        // The index points at a point at that distance (indices are the caller's).
        EXPECT_DOUBLE_EQ((points[found[i].index] - q).squaredNorm(), expected[i]);
      }
    }
  }
}

TEST(KdTree, KnnReturnsAllPointsWhenKExceedsSize) {
  const std::vector<Vec3> points = random_points(7, 3);
  const KdTree tree(points);
  EXPECT_EQ(tree.knn(Vec3::Zero(), 20).size(), 7u);
  EXPECT_TRUE(KdTree(std::vector<Vec3>{}).knn(Vec3::Zero(), 3).empty());
}

TEST(KdTree, NearestWithinRadiusEqualsBruteForce) {
  const std::vector<Vec3> points = random_points(800, 4);
  const KdTree tree(points);
  const double max_d2 = 0.05;
  int found_some = 0, found_none = 0;
  for (const Vec3& q : random_points(300, 5)) {
    const Neighbor n = tree.nearest(q + Vec3(0, 0.5, 0), max_d2);
    const double best = brute_force_distances(points, q + Vec3(0, 0.5, 0), 1)[0];
    if (best < max_d2) {
      ASSERT_GE(n.index, 0);
      EXPECT_DOUBLE_EQ(n.squared_distance_m2, best);
      ++found_some;
    } else {
      EXPECT_EQ(n.index, -1);
      ++found_none;
    }
  }
  EXPECT_GT(found_some, 0);  // both branches exercised
  EXPECT_GT(found_none, 0);
}

// The median split's branch-free selection must cope with repeated coordinates (a lattice,
// runs of equal values along the split axis) and fully coincident points: every point kept
// once, and k-NN still equal to brute force.
TEST(KdTree, RepeatedCoordinatesAndCoincidentPointsStillGiveExactKnn) {
  std::vector<Vec3> points;
  for (int x = 0; x < 9; ++x)
    for (int y = 0; y < 5; ++y)
      for (int z = 0; z < 7; ++z) points.push_back(Vec3(0.1 * x, 0.1 * y, 0.1 * z));
  for (int i = 0; i < 40; ++i) points.push_back(Vec3(0.3, 0.2, 0.1));  // coincident
  const KdTree tree(points);
  std::vector<int> order = tree.leaf_order();
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < order.size(); ++i) ASSERT_EQ(order[i], static_cast<int>(i));
  const std::vector<Vec3> queries = random_points(100, 7);
  for (int k : {1, 8, 50}) {
    for (const Vec3& q0 : queries) {
      const Vec3 q = 0.15 * q0 + Vec3(0.4, 0.2, 0.3);
      const std::vector<Neighbor> found = tree.knn(q, k);
      const std::vector<double> expected = brute_force_distances(points, q, k);
      ASSERT_EQ(found.size(), expected.size());
      for (std::size_t i = 0; i < found.size(); ++i)
        EXPECT_DOUBLE_EQ(found[i].squared_distance_m2, expected[i]);
    }
  }
}
