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

// The Newton / cross-product eigen solver behind plane_normals gives the same covariances as
// Eigen's iterative solver on real-like neighbourhoods (a curved, noisy car-like surface), and
// plane_covariance(n) is V diag(eps, 1, 1) V^T.
TEST(PlaneCovariances, ClosedFormSolverMatchesTheIterativeOne) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Vec3> points;
  for (int i = 0; i < 800; ++i) {  // a bent sheet: the normal turns across it
    const double x = 2.0 * u(rng), y = 0.8 * u(rng);
    points.push_back(Vec3(x, y, 0.15 * x * x + noise(rng)) + Vec3(3, 1, 12));
  }
  const KdTree tree(points);
  const std::vector<Vec3> normals = plane_normals(points, tree, 20);
  const std::vector<Mat3> cov = plane_covariances(points, tree, 20);
  std::vector<Neighbor> neighbors;
  for (std::size_t i = 0; i < points.size(); ++i) {
    tree.knn(points[i], 20, &neighbors);
    Vec3 mean = Vec3::Zero();
    for (const Neighbor& n : neighbors) mean += points[n.index];
    mean /= 20.0;
    Mat3 scatter = Mat3::Zero();
    for (const Neighbor& n : neighbors)
      scatter += (points[n.index] - mean) * (points[n.index] - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Mat3> iterative(scatter);
    const Mat3& V = iterative.eigenvectors();
    const Mat3 expected = V * Vec3(kPlaneEpsilon, 1.0, 1.0).asDiagonal() * V.transpose();
    EXPECT_NEAR(normals[i].norm(), 1.0, 1e-9);
    EXPECT_GT(std::abs(normals[i].dot(V.col(0))), 1.0 - 1e-6);  // same axis within ~0.1 deg
    EXPECT_TRUE(cov[i].isApprox(expected, 1e-5)) << i;
    EXPECT_TRUE(plane_covariance(normals[i]).isApprox(cov[i], 1e-12));
  }
}

// Degenerate neighbourhoods: points on a line (the two smallest eigenvalues equal) give a unit
// normal orthogonal to the line; a blob with three nearly equal axes gives the iterative
// solver's smallest axis.
TEST(PlaneCovariances, LinesAndNearlyIsotropicNeighbourhoods) {
  const Vec3 direction = Vec3(1.0, 2.0, -0.5).normalized();
  std::vector<Vec3> line;
  for (int i = 0; i < 40; ++i) line.push_back(Vec3(4, -1, 9) + 0.05 * i * direction);
  const KdTree line_tree(line);
  for (const Vec3& n : plane_normals(line, line_tree, 10)) {
    EXPECT_NEAR(n.norm(), 1.0, 1e-9);
    EXPECT_LT(std::abs(n.dot(direction)), 1e-6);
  }
  std::mt19937 rng(2);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> blob;
  for (int i = 0; i < 200; ++i) blob.push_back(Vec3(1.0 * g(rng), 0.97 * g(rng), 0.94 * g(rng)));
  const KdTree blob_tree(blob);
  const std::vector<Vec3> normals = plane_normals(blob, blob_tree, 200);  // all points: one axis
  Mat3 scatter = Mat3::Zero();
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : blob) mean += p / 200.0;
  for (const Vec3& p : blob) scatter += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Mat3> iterative(scatter);
  EXPECT_GT(std::abs(normals[0].dot(iterative.eigenvectors().col(0))), 1.0 - 1e-6);
}

// The closed-form information of two plane covariances (Woodbury, rank two) equals the
// generic 3x3 inverse of their sum, also for nearly parallel and antiparallel normals where
// it is stiffest (eigenvalue 1 / (2 eps) along the common normal).
TEST(PlaneCovariances, ClosedFormPairInformationEqualsTheInverse) {
  std::mt19937 rng(21);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    const Vec3 n = Vec3(g(rng), g(rng), g(rng)).normalized();
    Vec3 m = Vec3(g(rng), g(rng), g(rng)).normalized();
    if (trial % 3 == 1) m = (n + 1e-4 * m).normalized();   // nearly parallel
    if (trial % 3 == 2) m = (-n + 1e-4 * m).normalized();  // nearly antiparallel
    const Mat3 expected = (plane_covariance(n) + plane_covariance(m)).inverse();
    const PlanePairInformation info = plane_pair_information(n.dot(m));
    const Vec3 u = n + m, v = n - m;
    const Mat3 W = 0.5 * Mat3::Identity() + info.alpha_sum * u * u.transpose() +
                   info.alpha_diff * v * v.transpose();
    EXPECT_TRUE(W.isApprox(expected, 1e-9)) << trial << "\n" << W - expected;
  }
}
