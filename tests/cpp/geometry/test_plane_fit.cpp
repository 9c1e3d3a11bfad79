#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "geometry/plane_fit.hpp"

using namespace twistslam;
using namespace twistslam::geometry;

namespace {

// The point at in-plane coordinates (a, b) of the plane n.X + d = 0, lifted along n.
Vec3 point_on_plane(const Vec3& n, double d, double a, double b, double lift) {
  const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  return -d * n + a * e1 + b * e2 + lift * n;
}

}  // namespace

TEST(PlaneFit, RecoversRoadPlaneWithOutliers) {
  // Road 1.65 m below the camera (y down), tilted 2 degrees, 2 cm noise, 40 % outliers.
  const Vec3 n = Vec3(0.0, -std::cos(0.035), std::sin(0.035));
  const double d = 1.65;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  const int inliers = 600, outliers = 400;
  Points3 P(inliers + outliers, 3);
  for (int i = 0; i < inliers; ++i) {
    const double a = u(rng), b = u(rng);
    P.row(i) = point_on_plane(n, d, a, b, noise(rng)).transpose();
  }
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

// RANSAC stops scoring a sample once it can no longer beat the best one: the plane must be
// the one scoring every sample in full gives (a reference with the same sampler, here).
TEST(PlaneFit, StoppingHopelessSamplesEarlyKeepsTheExhaustiveResult) {
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-15.0, 15.0);
  std::normal_distribution<double> noise(0.0, 0.03);
  Points3 P(5000, 3);
  for (int i = 0; i < 5000; ++i) {
    if (i % 2 == 0) P.row(i) = Vec3(u(gen), 1.7 + noise(gen), u(gen) + 20).transpose();
    else P.row(i) = Vec3(u(gen), u(gen) * 0.1, u(gen) + 20).transpose();  // clutter
  }
  const PlaneFitOptions options{0.05, 120, 11};
  const PlaneFit fit = fit_plane_ransac(P, options);

  auto distance = [&](const Vec4& plane, Eigen::Index i) {
    return P(i, 0) * plane.x() + P(i, 1) * plane.y() + P(i, 2) * plane.z() + plane.w();
  };
  auto inliers_of = [&](const Vec4& plane) {
    std::vector<Eigen::Index> in;
    for (Eigen::Index i = 0; i < P.rows(); ++i)
      if (std::abs(distance(plane, i)) <= options.inlier_threshold) in.push_back(i);
    return in;
  };
  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<Eigen::Index> pick(0, P.rows() - 1);
  Vec4 best = Vec4::Zero();
  long best_count = -1;
  for (int it = 0; it < options.iterations; ++it) {
    const Vec3 a = P.row(pick(rng)), b = P.row(pick(rng)), c = P.row(pick(rng));
    const Vec3 normal = (b - a).cross(c - a);
    if (normal.norm() < 1e-12) continue;
    const Vec3 n = normal.normalized();
    const double d = -n.dot(a);
    const Vec4 candidate = d < 0 ? Vec4(-n.x(), -n.y(), -n.z(), -d) : Vec4(n.x(), n.y(), n.z(), d);
    const long count = static_cast<long>(inliers_of(candidate).size());
    if (count > best_count) best_count = count, best = candidate;
  }
  Vec4 plane = best;
  for (int round = 0; round < 2; ++round) {
    const std::vector<Eigen::Index> in = inliers_of(plane);
    Points3 Q(static_cast<Eigen::Index>(in.size()), 3);
    for (size_t k = 0; k < in.size(); ++k) Q.row(static_cast<Eigen::Index>(k)) = P.row(in[k]);
    plane = fit_plane_svd(Q);
  }
  EXPECT_EQ(fit.plane, plane);
  EXPECT_EQ(fit.num_inliers, static_cast<int>(inliers_of(plane).size()));
  EXPECT_GT(fit.num_inliers, 2000);  // the road half within 0.05 m: ~90 % at 3 cm noise
}

TEST(PlaneFit, ScoringAStridedSubsetFindsThePlaneOfAllPoints) {
  // 40k road points (2 cm noise) and 30 % clutter above it: hypotheses scored on 2000 points
  // give the plane of the exhaustive fit, as the refits use every point
  const Vec3 n = Vec3(0.0, -std::cos(0.02), std::sin(0.02));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  const int road = 40000, clutter = 17000;
  Points3 P(road + clutter, 3);
  for (int i = 0; i < road + clutter; ++i) {
    const double lift = i < road ? noise(rng) : 0.3 + std::abs(u(rng)) * 0.1;
    const double a = u(rng), b = u(rng);
    P.row(i) = point_on_plane(n, 1.65, a, b, lift).transpose();
  }
  PlaneFitOptions all{0.06, 200, 0}, strided{0.06, 200, 0};
  strided.max_scored_points = 2000;
  const PlaneFit a = fit_plane_ransac(P, all), b = fit_plane_ransac(P, strided);
  EXPECT_GT(b.plane.head<3>().dot(n), 0.99999);
  EXPECT_NEAR(b.plane.w(), 1.65, 0.005);
  EXPECT_GT(a.plane.head<3>().dot(b.plane.head<3>()), 0.999999);
  EXPECT_NEAR(a.plane.w(), b.plane.w(), 0.002);
  EXPECT_NEAR(b.num_inliers, a.num_inliers, 0.002 * road);
}
