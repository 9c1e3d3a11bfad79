// Plane normals eight at a time (smallest_eigenvectors.hpp) against Eigen's self-adjoint
// solver: planar, line-like (two nearly equal small eigenvalues: Newton's slow case, finished
// one by one after the block's steps) and random scatters, counts that fill the blocks and that
// leave a partial one; isotropic and zero matrices give the unit x axis.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <random>

#include "registration/smallest_eigenvectors.hpp"

using namespace twistslam;
using namespace twistslam::registration;

namespace {

// A random rotation of diag(l0, l1, l2).
Mat3 rotated(double l0, double l1, double l2, std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  const Mat3 R = q.normalized().toRotationMatrix();
  return R * Vec3(l0, l1, l2).asDiagonal() * R.transpose();
}

void push(const Mat3& A, SymmetricMatrices* m) {
  m->a00.push_back(A(0, 0)), m->a01.push_back(A(0, 1)), m->a02.push_back(A(0, 2));
  m->a11.push_back(A(1, 1)), m->a12.push_back(A(1, 2)), m->a22.push_back(A(2, 2));
}

}  // namespace

TEST(SmallestEigenvectors, MatchEigensSolverOnPlanesLinesAndRandomScatters) {
  for (const int count : {1, 8, 13, 100}) {
    std::mt19937 rng(count);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    SymmetricMatrices m;
    std::vector<Mat3> matrices;
    for (int k = 0; k < count; ++k) {
      Mat3 A;
      switch (k % 3) {
        case 0: A = rotated(1.0, 0.8, 1e-4 * u(rng), rng); break;          // a plane
        case 1: A = rotated(1.0, 1e-3, 1e-3 * (1.0 + 1e-3 * u(rng)), rng); break;  // a line
        default: A = rotated(u(rng), u(rng), u(rng), rng); break;
      }
      matrices.push_back(A);
      push(A, &m);
    }
    const std::vector<Vec3> normals = smallest_eigenvectors(m);
    ASSERT_EQ(static_cast<int>(normals.size()), count);
    for (int k = 0; k < count; ++k) {
      const Eigen::SelfAdjointEigenSolver<Mat3> solver(matrices[k]);
      const Vec3 expected = solver.eigenvectors().col(0);  // ascending eigenvalues
      EXPECT_NEAR(normals[k].norm(), 1.0, 1e-12) << k;
      const double gap = solver.eigenvalues()[1] - solver.eigenvalues()[0];
      // the eigenvector is defined up to the gap between the two smallest eigenvalues
      const double tolerance = k % 3 == 1 ? 1e-2 : 1e-6;
      if (gap > 1e-6) EXPECT_GT(std::abs(normals[k].dot(expected)), 1.0 - tolerance) << count << " " << k;
      // it is an eigenvector of the smallest eigenvalue: A n ~ l0 n
      EXPECT_LT((matrices[k] * normals[k] - solver.eigenvalues()[0] * normals[k]).norm(),
                1e-6 + 2.0 * gap) << count << " " << k;
    }
  }
  SymmetricMatrices special;
  push(Mat3::Identity(), &special);
  push(Mat3::Zero(), &special);
  for (const Vec3& n : smallest_eigenvectors(special)) EXPECT_EQ(n, Vec3::UnitX());
  EXPECT_TRUE(smallest_eigenvectors(SymmetricMatrices()).empty());
}
