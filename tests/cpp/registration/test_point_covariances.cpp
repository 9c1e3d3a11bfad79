// Plane covariances: the smallest axis is the plane normal, eigenvalues are (eps, 1, 1).
#include <gtest/gtest.h>

#include <random>

#include "registration/point_covariances.hpp"

using namespace twistslam;
using namespace twistslam::registration;

TEST(PlaneCovariances, SmallestAxisIsThePlaneNormal) {
  const Vec3 normal = Vec3(0.3, -1.0, 0.2).normalized();
  const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> in_plane(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<Vec3> points;
  for (int i = 0; i < 500; ++i)
    points.push_back(Vec3(1, 2, 10) + in_plane(rng) * u + in_plane(rng) * v + noise(rng) * normal);
  const KdTree tree(points);
  const std::vector<Mat3> cov = plane_covariances(points, tree, 20);
  ASSERT_EQ(cov.size(), points.size());
  for (const Mat3& C : cov) {
    Eigen::SelfAdjointEigenSolver<Mat3> eig(C);
    EXPECT_NEAR(eig.eigenvalues()[0], kPlaneEpsilon, 1e-9);
    EXPECT_NEAR(eig.eigenvalues()[1], 1.0, 1e-9);
    EXPECT_NEAR(eig.eigenvalues()[2], 1.0, 1e-9);
    EXPECT_GT(std::abs(eig.eigenvectors().col(0).dot(normal)), 0.99);  // within ~8 deg
  }
}

TEST(PlaneCovariances, RefusesTooFewPoints) {
  const std::vector<Vec3> points(5, Vec3::Zero());
  const KdTree tree(points);
  EXPECT_THROW(plane_covariances(points, tree, 20), std::invalid_argument);
  EXPECT_THROW(plane_covariances(points, tree, 2), std::invalid_argument);
  // Coincident points: an arbitrary plane, but finite numbers.
  for (const Mat3& C : plane_covariances(points, tree, 5)) EXPECT_TRUE(C.allFinite());
}
