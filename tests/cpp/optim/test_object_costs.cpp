// Private pieces of cpp/optim for the object terms of eq. 9: the templated SE(3) log of
// se3_jet.hpp against geometry::se3_log, and the autodiff Jacobians of the four object costs
// (object_costs.hpp) against central differences, in the 7 ambient coordinates and through
// the manifold tangent, at generic, tiny (1e-9 rad) and large (~3 rad) relative rotations.
#include <gtest/gtest.h>

#include <ceres/autodiff_cost_function.h>

#include <array>
#include <memory>
#include <random>
#include <vector>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "optim/object_costs.hpp"
#include "optim/problem_builder.hpp"

using namespace twistslam;
using namespace twistslam::optim::detail;

namespace {

using Pose = std::array<double, 7>;

Pose params(const Mat4& T) {
  Pose p;
  pose_to_params(T, p.data());
  return p;
}

Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

// exp([t * a; angle * b]) with random unit a, b.
Mat4 random_motion(double t, double angle, std::mt19937& rng) {
  Vec6 xi;
  xi << t * random_unit(rng), angle * random_unit(rng);
  return geometry::se3_exp(xi);
}

// Three poses whose consecutive relative rotations have the given angle.
std::vector<Mat4> chain(double angle, std::mt19937& rng) {
  std::vector<Mat4> T{random_motion(8.0, 2.0, rng)};
  for (int i = 0; i < 2; ++i) T.push_back(random_motion(1.5, angle, rng) * T.back());
  return T;
}

// Compares the cost's Jacobian of every block with central differences, in the ambient
// coordinates (7) and through the manifold's Plus (6).
void check_jacobians(const ceres::CostFunction& cost, std::vector<Pose> poses,
                     const char* label) {
  SCOPED_TRACE(label);
  const int nb = static_cast<int>(poses.size());
  ASSERT_EQ(cost.parameter_block_sizes().size(), poses.size());
  using Jac = Eigen::Matrix<double, 6, 7, Eigen::RowMajor>;
  std::vector<Jac> J(nb);
  std::vector<const double*> p(nb);
  std::vector<double*> jp(nb);
  for (int k = 0; k < nb; ++k) p[k] = poses[k].data(), jp[k] = J[k].data();
  Vec6 r0;
  ASSERT_TRUE(cost.Evaluate(p.data(), r0.data(), jp.data()));
  auto eval = [&](int k, const Pose& x) {
    std::vector<const double*> q = p;
    q[k] = x.data();
    Vec6 r;
    EXPECT_TRUE(cost.Evaluate(q.data(), r.data(), nullptr));
    return r;
  };
  PoseManifold manifold;
  const double h = 1e-6;
  for (int k = 0; k < nb; ++k) {
    const double scale = 1.0 + J[k].norm();
    for (int i = 0; i < 7; ++i) {  // ambient
      Pose plus = poses[k], minus = poses[k];
      plus[i] += h;
      minus[i] -= h;
      const Vec6 num = (eval(k, plus) - eval(k, minus)) / (2 * h);
      EXPECT_LT((num - J[k].col(i)).norm(), 1e-7 * scale) << "block " << k << " coord " << i;
    }
    Eigen::Matrix<double, 7, 6, Eigen::RowMajor> P;
    ASSERT_TRUE(manifold.PlusJacobian(poses[k].data(), P.data()));
    const Eigen::Matrix<double, 6, 6> Jt = J[k] * P;
    for (int i = 0; i < 6; ++i) {  // tangent
      double d[6] = {0, 0, 0, 0, 0, 0};
      Pose plus, minus;
      d[i] = h;
      manifold.Plus(poses[k].data(), d, plus.data());
      d[i] = -h;
      manifold.Plus(poses[k].data(), d, minus.data());
      const Vec6 num = (eval(k, plus) - eval(k, minus)) / (2 * h);
      EXPECT_LT((num - Jt.col(i)).norm(), 1e-7 * scale) << "block " << k << " tangent " << i;
    }
  }
}

const Vec3 kTiltedNormal = Vec3(0.1, -1.0, 0.2).normalized();

}  // namespace

TEST(ObjectSe3Jet, RelativeTwistEqualsGeometryLog) {
  std::mt19937 rng(3);
  // Generic, tiny, around the series switch (2e-3 rad), large and close to pi.
  for (double angle : {0.0, 1e-12, 1e-9, 1e-6, 1.9e-3, 2.1e-3, 0.3, 1.0, 2.0, 3.0, 3.14}) {
    for (int trial = 0; trial < 20; ++trial) {
      const Mat4 Ta = random_motion(10.0, 2.5, rng);
      const Mat4 Tb = random_motion(trial % 2 ? 0.01 : 3.0, angle, rng) * Ta;
      const Pose pa = params(Ta), pb = params(Tb);
      const Vec6 xi = relative_twist(pa.data(), pb.data());
      const Vec6 ref = geometry::twist_between(Ta, Tb);
      EXPECT_LT((xi - ref).norm(), 1e-10 * (1 + ref.norm())) << "angle " << angle;
      // exp(xi) T_a == T_b: the log is the right one, not just consistent with se3_log.
      EXPECT_LT((geometry::se3_exp(xi) * Ta - Tb).norm(), 1e-9) << "angle " << angle;
      double theta2;
      const Vec3 w = quaternion_log(pose_quaternion(pb.data()), &theta2);
      EXPECT_LT((w - geometry::so3_log(Tb.topLeftCorner<3, 3>())).norm(), 1e-10);
      EXPECT_NEAR(theta2, w.squaredNorm(), 1e-12);
    }
  }
  // Unnormalised quaternions and the -q sign give the same twist.
  const Mat4 Ta = random_motion(2.0, 1.0, rng), Tb = random_motion(1.0, 0.5, rng) * Ta;
  Pose pa = params(Ta), pb = params(Tb);
  for (int i = 3; i < 7; ++i) pa[i] *= -2.5, pb[i] *= 0.7;
  EXPECT_LT((relative_twist(pa.data(), pb.data()) - geometry::twist_between(Ta, Tb)).norm(),
            1e-12);
}

namespace {
struct RelativeTwistFunctor {  // xi~ on Jets: the templated log is autodiff-ready
  template <typename T>
  bool operator()(const T* a, const T* b, T* residuals) const {
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residuals);
    r = relative_twist(a, b);
    return true;
  }
};
}  // namespace

// The analytic Jacobians of xi~ (object_costs.hpp) equal autodiff of the templated log to
// ~1e-9, a tighter check than central differences, over the same angle regimes.
TEST(ObjectCosts, AnalyticTwistJacobiansEqualAutodiff) {
  std::mt19937 rng(11);
  ceres::AutoDiffCostFunction<RelativeTwistFunctor, 6, 7, 7> autodiff(new RelativeTwistFunctor);
  for (double angle : {1e-9, 1e-4, 2e-3, 0.5, 3.0}) {
    for (int trial = 0; trial < 5; ++trial) {
      const auto T = chain(angle, rng);
      const Pose a = params(T[0]), b = params(T[1]);
      const double* p[2] = {a.data(), b.data()};
      Eigen::Matrix<double, 6, 7, Eigen::RowMajor> Ja_auto, Jb_auto, Ja, Jb;
      double* J[2] = {Ja_auto.data(), Jb_auto.data()};
      Vec6 r;
      ASSERT_TRUE(autodiff.Evaluate(p, r.data(), J));
      Mat6 Ta, Tb;
      const Vec6 xi = relative_twist_jacobians(a.data(), b.data(), &Ta, &Tb);
      tangent_to_ambient(Ta, a.data(), Ja.data());
      tangent_to_ambient(Tb, b.data(), Jb.data());
      EXPECT_LT((xi - r).norm(), 1e-14 * (1 + r.norm()));
      EXPECT_LT((Ja - Ja_auto).norm(), 1e-9 * (1 + Ja.norm())) << "angle " << angle;
      EXPECT_LT((Jb - Jb_auto).norm(), 1e-9 * (1 + Jb.norm())) << "angle " << angle;
    }
  }
}

TEST(ObjectCosts, JacobiansMatchCentralDifferences) {
  std::mt19937 rng(7);
  const Mat6 planar = geometry::projector_planar(kTiltedNormal);
  const Mat6 free = geometry::projector_free();
  struct Case { double angle; const char* label; };
  for (const Case c : {Case{0.4, "generic"}, Case{1e-9, "tiny 1e-9 rad"},
                       Case{2e-3, "series switch"}, Case{3.0, "large 3 rad"}}) {
    for (int trial = 0; trial < 4; ++trial) {
      const auto T = chain(c.angle, rng);
      const Mat6& Pi = trial % 2 ? planar : free;
      const Vec6 xi_d = geometry::twist_between(T[0], T[1]) +
                        0.05 * Vec6::Random();  // a measurement with an error
      // Unit sigmas keep the Jacobians O(1) so one tolerance fits all; sigmas scale rows.
      std::unique_ptr<ceres::CostFunction> costs[] = {
          std::unique_ptr<ceres::CostFunction>(make_constant_velocity_cost(Pi, 1.0, 1.0)),
          std::unique_ptr<ceres::CostFunction>(make_detection_twist_cost(Pi, xi_d, 1.0, 1.0)),
          std::unique_ptr<ceres::CostFunction>(make_link_cost(Pi, 1.0, 1.0)),
          std::unique_ptr<ceres::CostFunction>(
              make_detection_pose_cost(random_motion(0.3, c.angle, rng) * T[0], 1.0, 1.0))};
      check_jacobians(*costs[0], {params(T[0]), params(T[1]), params(T[2])}, c.label);
      check_jacobians(*costs[1], {params(T[0]), params(T[1])}, c.label);
      check_jacobians(*costs[2], {params(T[0]), params(T[1])}, c.label);
      check_jacobians(*costs[3], {params(T[0])}, c.label);
    }
  }
}

TEST(ObjectCosts, ZeroOnAConstantTwistPlanarTrajectory) {
  // A car turning on a plane (normal -y of the camera: y points down): xi in Pi's sub-space.
  const Vec3 n(0, -1, 0);
  const Mat6 Pi = geometry::projector_planar(n);
  Vec6 xi;
  xi << 0.3, 0.0, 1.0, 0.0, 0.05, 0.0;
  xi = Pi * xi;
  const Mat4 T0 = geometry::make_pose(geometry::so3_exp(Vec3(0, 0.7, 0)), Vec3(2, 1.6, 12));
  std::vector<Mat4> T{T0};
  for (int i = 0; i < 3; ++i) T.push_back(geometry::se3_exp(xi) * T.back());
  const Pose p0 = params(T[0]), p1 = params(T[1]), p2 = params(T[2]);
  const double* three[] = {p0.data(), p1.data(), p2.data()};
  Vec6 r;
  std::unique_ptr<ceres::CostFunction> c(make_constant_velocity_cost(Pi, 0.3, 0.03));
  ASSERT_TRUE(c->Evaluate(three, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9);
  c.reset(make_detection_twist_cost(Pi, xi, 0.3, 0.1));
  ASSERT_TRUE(c->Evaluate(three, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9);
  c.reset(make_link_cost(Pi, 0.01, 0.002));
  ASSERT_TRUE(c->Evaluate(three, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9);
  c.reset(make_detection_pose_cost(T[1], 0.3, 0.1, 4.0));
  ASSERT_TRUE(c->Evaluate(three + 1, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9);

  // A 0.5 m vertical jump (along the normal) between two frames: the link sees 0.5 / sigma_t
  // in its translation rows, the planar projector hides it from e_det.
  Mat4 jumped = T[2];
  jumped.topRightCorner<3, 1>() += 0.5 * n;
  const Pose pj = params(jumped);
  const double* jump[] = {p1.data(), pj.data()};
  c.reset(make_link_cost(Pi, 0.01, 0.002));
  ASSERT_TRUE(c->Evaluate(jump, r.data(), nullptr));
  EXPECT_NEAR(r.head<3>().norm(), 0.5 / 0.01, 1e-6);
  EXPECT_LT(r.tail<3>().norm(), 1e-9);
  c.reset(make_detection_twist_cost(Pi, xi, 0.3, 0.1));
  ASSERT_TRUE(c->Evaluate(jump, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9);
  // A detection pose off by (0.3 m, 0.1 rad): whitened residual (1, 1) times sqrt(4).
  c.reset(make_detection_pose_cost(geometry::make_pose(geometry::so3_exp(Vec3(0, 0.1, 0)),
                                                       Vec3(0.3, 0, 0)) * T[1], 0.3, 0.1, 4.0));
  ASSERT_TRUE(c->Evaluate(three + 1, r.data(), nullptr));
  EXPECT_NEAR(r.tail<3>().norm(), 2.0, 1e-9);
}

TEST(ObjectProblemBuilder, AddsTheObjectFamiliesAndRejectsBadSigmas) {
  ProblemBuilder b;
  const Mat6 Pi = geometry::projector_planar(Vec3(0, -1, 0));
  const int a = b.add_pose(Mat4::Identity(), true);
  const int c = b.add_pose(Mat4::Identity(), false);
  const int d = b.add_pose(Mat4::Identity(), false);
  EXPECT_NE(b.add_constant_velocity(a, c, d, Pi, 0.3, 0.03, 3.0), nullptr);
  EXPECT_NE(b.add_detection_twist(a, c, Pi, Vec6::Zero(), 0.3, 0.1, 2.0, 0.5), nullptr);
  EXPECT_NE(b.add_detection_pose(c, Mat4::Identity(), 0.3, 0.1, 2.0), nullptr);
  EXPECT_NE(b.add_link(c, d, Pi, 0.01, 0.002), nullptr);
  EXPECT_EQ(b.num_residuals(), 4);
  EXPECT_THROW(b.add_link(c, d, Pi, 0.0, 0.002), std::invalid_argument);
  EXPECT_THROW(b.add_detection_pose(c, Mat4::Identity(), 0.3, 0.1, 2.0, -1.0),
               std::invalid_argument);
  EXPECT_EQ(b.num_residuals(), 4);
}

TEST(ObjectCosts, ATwistMeasurementIsWhitenedByItsFullCovarianceAndBlindWhereItHasNone) {
  // covariance: 1 cm along x, 10 cm along z, 0.01 rad of yaw (about y), correlated x-yaw; zero
  // along y and in roll / pitch (the planar link)
  Mat6 C = Mat6::Zero();
  C(0, 0) = 1e-4;
  C(2, 2) = 1e-2;
  C(4, 4) = 1e-4;
  C(0, 4) = C(4, 0) = 0.5e-4;
  const Mat6 L = twist_sqrt_information(C);
  // L^T L is the pseudo-inverse: C L^T L C = C, and the null directions get no weight
  EXPECT_LT((C * L.transpose() * L * C - C).norm(), 1e-12);
  EXPECT_LT((L * Vec6::Unit(1)).norm(), 1e-9);
  EXPECT_LT((L * Vec6::Unit(3)).norm(), 1e-9);
  // an error of 1 cm along x alone is worth sqrt(e^T C^+ e) sigmas
  const Pose p0 = params(Mat4::Identity()), p1 = params(Mat4::Identity());
  const double* two[] = {p0.data(), p1.data()};
  Vec6 e = Vec6::Zero();
  e(0) = 0.01;
  std::unique_ptr<ceres::CostFunction> cost(make_twist_measurement_cost(C, e));
  Vec6 r;
  ASSERT_TRUE(cost->Evaluate(two, r.data(), nullptr));
  const Eigen::Matrix2d C_xyaw = (Eigen::Matrix2d() << 1e-4, 0.5e-4, 0.5e-4, 1e-4).finished();
  EXPECT_NEAR(r.norm(), std::sqrt(Vec2(0.01, 0).dot(C_xyaw.inverse() * Vec2(0.01, 0))), 1e-9);
  // a jump along the null direction (y) costs nothing
  Mat4 up = Mat4::Identity();
  up(1, 3) = 0.5;
  const Pose pu = params(up);
  const double* jump[] = {p0.data(), pu.data()};
  cost.reset(make_twist_measurement_cost(C, Vec6::Zero()));
  ASSERT_TRUE(cost->Evaluate(jump, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9);
  // a covariance that is not finite, or has no variance, is refused
  EXPECT_THROW(twist_sqrt_information(Mat6::Zero()), std::invalid_argument);
  Mat6 bad = C;
  bad(2, 2) = NAN;
  EXPECT_THROW(twist_sqrt_information(bad), std::invalid_argument);
  ProblemBuilder b;
  const int a = b.add_pose(Mat4::Identity(), true);
  const int c = b.add_pose(Mat4::Identity(), false);
  EXPECT_NE(b.add_twist_measurement(a, c, Vec6::Zero(), C, 2.0), nullptr);
  EXPECT_THROW(b.add_twist_measurement(a, c, Vec6::Zero(), bad, 2.0), std::invalid_argument);
  EXPECT_EQ(b.num_residuals(), 1);
}
