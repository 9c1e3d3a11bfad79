// SO(3)/SE(3): closed forms against numerical derivatives, at tiny angles and near pi.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"

using namespace twistslam;
using namespace twistslam::geometry;

namespace {

Vec6 random_twist(std::mt19937& rng, double angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec6 xi;
  for (int i = 0; i < 6; ++i) xi[i] = n(rng);
  xi.tail<3>() = xi.tail<3>().normalized() * angle;
  return xi;
}

// Numerical left Jacobian: column k = log(exp(xi + h e_k) exp(xi)^-1) / h (central).
Mat6 numeric_left_jacobian(const Vec6& xi) {
  const double h = 1e-6;
  Mat6 J;
  for (int k = 0; k < 6; ++k) {
    Vec6 d = Vec6::Zero();
    d[k] = h;
    const Vec6 plus = se3_log(se3_exp(xi + d) * se3_inverse(se3_exp(xi)));
    const Vec6 minus = se3_log(se3_exp(xi - d) * se3_inverse(se3_exp(xi)));
    J.col(k) = (plus - minus) / (2 * h);
  }
  return J;
}

class AngleTest : public ::testing::TestWithParam<double> {};

}  // namespace

TEST_P(AngleTest, ExpLogRoundTrip) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec6 xi = random_twist(rng, GetParam());
    const Mat4 T = se3_exp(xi);
    EXPECT_TRUE(is_rigid_transform(T, 1e-12));
    const Vec6 back = se3_log(T);
    // Near pi the rotation vector's sign is ambiguous; compare the transforms as well.
    EXPECT_LT((se3_exp(back) - T).cwiseAbs().maxCoeff(), 1e-9);
    if (GetParam() < 3.1) EXPECT_LT((back - xi).norm(), 1e-9 * std::max(1.0, xi.norm()));
  }
}

TEST_P(AngleTest, LeftJacobianMatchesNumeric) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 10; ++trial) {
    const Vec6 xi = random_twist(rng, GetParam());
    const Mat6 J = se3_left_jacobian(xi);
    EXPECT_LT((J - numeric_left_jacobian(xi)).cwiseAbs().maxCoeff(), 1e-6) << xi.transpose();
    EXPECT_LT((se3_left_jacobian_inverse(xi) * J - Mat6::Identity()).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((se3_right_jacobian(xi) - se3_left_jacobian(-xi)).norm(), 1e-15);
    EXPECT_LT((se3_right_jacobian_inverse(xi) * se3_right_jacobian(xi) - Mat6::Identity()).norm(),
              1e-9);
  }
}

INSTANTIATE_TEST_SUITE_P(Angles, AngleTest,
                         ::testing::Values(0.0, 1e-9, 1e-6, 1e-4 * 0.99, 1e-4 * 1.01, 0.3, 1.5,
                                           3.0, M_PI - 1e-6, M_PI - 1e-9));

TEST(So3, LogNearPiKeepsAxis) {
  const Vec3 axis = Vec3(1, -2, 0.5).normalized();
  for (double eps : {1e-3, 1e-6, 1e-9, 0.0}) {
    const Vec3 w = so3_log(so3_exp(axis * (M_PI - eps)));
    EXPECT_NEAR(w.norm(), M_PI - eps, 1e-9);
    EXPECT_NEAR(std::abs(w.normalized().dot(axis)), 1.0, 1e-9);
  }
}

TEST(So3, ExpMatchesEigenAngleAxis) {
  const Vec3 w(0.3, -0.2, 0.9);
  const Mat3 R = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  EXPECT_LT((so3_exp(w) - R).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(Se3, AdjointConjugatesTwists) {
  std::mt19937 rng(3);
  const Mat4 T = se3_exp(random_twist(rng, 0.8));
  const Vec6 xi = random_twist(rng, 0.4);
  const Mat4 lhs = se3_exp(se3_adjoint(T) * xi);
  const Mat4 rhs = T * se3_exp(xi) * se3_inverse(T);
  EXPECT_LT((lhs - rhs).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Se3, TwistBetweenIsLeftIncrement) {
  std::mt19937 rng(5);
  const Mat4 Ta = se3_exp(random_twist(rng, 1.0));
  const Vec6 xi = random_twist(rng, 0.2);
  const Mat4 Tb = se3_exp(xi) * Ta;
  EXPECT_LT((twist_between(Ta, Tb) - xi).norm(), 1e-12);
}

TEST(Se3, InverseAndRigidCheck) {
  std::mt19937 rng(9);
  const Mat4 T = se3_exp(random_twist(rng, 2.0));
  EXPECT_LT((se3_inverse(T) * T - Mat4::Identity()).cwiseAbs().maxCoeff(), 1e-14);
  Mat4 bad = T;
  bad(0, 0) += 0.1;
  EXPECT_FALSE(is_rigid_transform(bad));
  bad = T;
  bad(3, 0) = 1;
  EXPECT_FALSE(is_rigid_transform(bad));
}

TEST(RigidTransform, ProblemsAreNamed) {
  const Mat4 T = se3_exp((Vec6() << 1, -2, 3, 0.3, -0.2, 0.1).finished());
  EXPECT_EQ(rigid_transform_problem(T, 1e-9), "");
  EXPECT_TRUE(is_rigid_transform(T));
  Mat4 scaled = T;
  scaled.topLeftCorner<3, 3>() *= 3.0;
  EXPECT_EQ(rigid_transform_problem(scaled, 1e-4), "R^T R differs from I by 8");
  EXPECT_FALSE(is_rigid_transform(scaled));
  Mat4 reflected = Mat4::Identity();
  reflected(2, 2) = -1;
  EXPECT_EQ(rigid_transform_problem(reflected, 1e-4), "det R = -1 (a reflection)");
  Mat4 projective = T;
  projective(3, 0) = 0.5;
  EXPECT_EQ(rigid_transform_problem(projective, 1e-4), "last row is not [0, 0, 0, 1]");
  Mat4 nan = T;
  nan(1, 3) = std::nan("");
  EXPECT_EQ(rigid_transform_problem(nan, 1e-4), "contains NaN or Inf");
  EXPECT_EQ(rotation_problem(Mat3::Ones(), 1e-4).rfind("R^T R differs from I by ", 0), 0u);
  // text-file precision (6 digits) passes a 1e-4 tolerance
  Mat4 rounded = T;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rounded(i, j) = std::round(T(i, j) * 1e6) / 1e6;
  EXPECT_EQ(rigid_transform_problem(rounded, 1e-4), "");
}

TEST(ConstantVelocity, RepeatsTheLastMotionInEitherConvention) {
  const Mat4 T_a = se3_exp((Vec6() << 0.5, 0.1, -2, 0.1, 0.4, -0.2).finished());
  const Mat4 motion = se3_exp((Vec6() << 0, 0, 0.9, 0, 0.03, 0).finished());
  const Mat4 T_b = motion * T_a;
  const Mat4 predicted = predict_constant_velocity(T_a, T_b);
  EXPECT_LT((predicted - motion * T_b).cwiseAbs().maxCoeff(), 1e-12);
  const Mat4 inverse = predict_constant_velocity(se3_inverse(T_a), se3_inverse(T_b));
  EXPECT_LT((inverse - se3_inverse(predicted)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(So3, HatIsTheCrossProduct) {
  const Vec3 a(0.3, -1.2, 2.0), b(-0.7, 0.4, 1.1);
  EXPECT_LT((hat(a) * b - a.cross(b)).norm(), 1e-15);
  EXPECT_LT((vee(hat(a)) - a).norm(), 1e-15);
}
