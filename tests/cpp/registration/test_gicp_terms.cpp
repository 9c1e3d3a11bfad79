// GICP's normal equations summed eight pairs at a time (gicp_terms.hpp) against the dense
// per-pair formula: H = sum w J^T W J, b = sum w J^T W e, cost = sum rho(e^T W e), with
// W = (C_t + C_s)^-1 of the two plane covariances and J = [-I, hat(q)]; for counts that fill
// the blocks and that leave a partial one, with and without the Huber kernel.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/so3.hpp"
#include "registration/gicp_terms.hpp"
#include "registration/point_covariances.hpp"

using namespace twistslam;
using namespace twistslam::registration;

namespace {

Vec3 unit(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

}  // namespace

TEST(GicpTerms, BlockSumsEqualTheDensePerPairSums) {
  for (const int count : {1, 7, 8, 9, 37}) {
    for (const bool huber : {false, true}) {
      std::mt19937 rng(count * 2 + huber);
      std::normal_distribution<double> offset(0.0, 0.05), spread(0.0, 3.0);
      const double threshold = 0.05;
      GicpTerms terms;
      terms.reset(count);
      Mat6 H = Mat6::Zero();
      Vec6 b = Vec6::Zero();
      double cost = 0.0, sse = 0.0;
      for (int k = 0; k < count; ++k) {
        const Vec3 q(spread(rng), spread(rng), 10.0 + spread(rng));
        const Vec3 e(offset(rng), offset(rng), offset(rng));
        const Vec3 n = unit(rng), m = unit(rng);
        terms.add(q, e, n, m);
        const Mat3 W = (plane_covariance(n) + plane_covariance(m)).inverse();
        Eigen::Matrix<double, 3, 6> J;
        J << -Mat3::Identity(), geometry::hat(q);
        const double m2 = e.dot(W * e), r = std::sqrt(m2);
        const double w = huber && r > threshold ? threshold / r : 1.0;
        H += w * J.transpose() * W * J;
        b += w * J.transpose() * W * e;
        cost += huber && r > threshold ? threshold * (2.0 * r - threshold) : m2;
        sse += e.squaredNorm();
      }
      const GicpNormalEquations sums = sum_normal_equations(terms, huber, threshold);
      EXPECT_TRUE(sums.H.isApprox(H, 1e-9)) << count << " " << huber << "\n" << sums.H - H;
      EXPECT_TRUE(sums.b.isApprox(b, 1e-9)) << count << " " << huber;
      EXPECT_NEAR(sums.cost, cost, 1e-9 * cost) << count << " " << huber;
      EXPECT_NEAR(sums.sum_squared_error_m2, sse, 1e-12) << count;
      // the same terms summed again (padding left in place) give the same answer
      const GicpNormalEquations again = sum_normal_equations(terms, huber, threshold);
      EXPECT_EQ(again.H, sums.H);
    }
  }
  GicpTerms none;
  const GicpNormalEquations zero = sum_normal_equations(none, false, 0.1);
  EXPECT_EQ(zero.H, Mat6::Zero());
  EXPECT_EQ(zero.cost, 0.0);
}
