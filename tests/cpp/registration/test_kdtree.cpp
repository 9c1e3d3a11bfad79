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
