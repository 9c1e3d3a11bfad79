#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "geometry/plane_fit.hpp"

using namespace twistslam;
using namespace twistslam::geometry;

TEST(PlaneFit, RecoversRoadPlaneWithOutliers) {
  // Road 1.65 m below the camera (y down), tilted 2 degrees, 2 cm noise, 40 % outliers.
  const Vec3 n = Vec3(0.0, -std::cos(0.035), std::sin(0.035));
  const double d = 1.65;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  const int inliers = 600, outliers = 400;
  Points3 P(inliers + outliers, 3);
  const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  for (int i = 0; i < inliers; ++i)
    P.row(i) = (-d * n + u(rng) * e1 + u(rng) * e2 + noise(rng) * n).transpose();
  for (int i = inliers; i < inliers + outliers; ++i) P.row(i) = Vec3(u(rng), u(rng) * 0.2 - 3, u(rng) + 25).transpose();

  const PlaneFit fit = fit_plane_ransac(P, {0.06, 300, 0});
  EXPECT_GT(fit.plane.head<3>().dot(n), 0.99999);
  EXPECT_NEAR(fit.plane.w(), d, 0.01);
  int true_in = 0;
  for (int i = 0; i < inliers; ++i) true_in += fit.inliers[i];
  EXPECT_GT(true_in, 0.97 * inliers);
  EXPECT_LT(fit.num_inliers, inliers + 0.05 * outliers);
  EXPECT_NEAR(fit.rms, 0.02, 0.006);
}

TEST(PlaneFit, DeterministicForASeedAndRejectsBadInput) {
  Points3 P(5, 3);
  P << 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1, 0.5, 0.5, 1.01;
  const PlaneFit a = fit_plane_ransac(P, {0.05, 50, 3}), b = fit_plane_ransac(P, {0.05, 50, 3});
  EXPECT_EQ(a.plane, b.plane);
  EXPECT_THROW(fit_plane_ransac(P.topRows(2)), std::invalid_argument);
  Points3 Q = P;
  Q(2, 1) = NAN;
  EXPECT_THROW(fit_plane_ransac(Q), std::invalid_argument);
  Points3 line(4, 3);
  line << 0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3;
  EXPECT_THROW(fit_plane_ransac(line), std::invalid_argument);
}
