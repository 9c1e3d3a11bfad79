// e_dyna of paper eq. 9 (dynamic_reprojection_cost.hpp): X_c = T_c_w T_w_o X_o.
// The analytic Jacobians against central differences (ambient and manifold tangent, stereo
// and mono), agreement with e_stat when the object frame is the world, a tiny BA of a moving
// object through ProblemBuilder::add_dynamic_reprojection, cheirality (min_depth) handled
// like e_stat, and the camera's disparity_offset.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <random>
#include <vector>

#include "common/kitti_camera.hpp"
#include "geometry/se3.hpp"
#include "optim/dynamic_reprojection_cost.hpp"
#include "optim/problem_builder.hpp"
#include "optim/reprojection_costs.hpp"

using namespace twistslam;
using namespace twistslam::optim::detail;

namespace {

using Pose = std::array<double, kPoseSize>;

Pose params(const Mat4& T) {
  Pose p;
  pose_to_params(T, p.data());
  return p;
}

Mat4 random_pose(double t, double angle, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Vec6 xi;
  xi << t * Vec3(n(rng), n(rng), n(rng)).normalized(),
      angle * Vec3(n(rng), n(rng), n(rng)).normalized();
  return geometry::se3_exp(xi);
}

Vec3 transform(const Mat4& T, const Vec3& X) {
  return T.topLeftCorner<3, 3>() * X + T.topRightCorner<3, 1>();
}

// A scene where the object point lands at X_c in front of the camera.
struct Scene {
  Pose camera, object;  // T_c_w, T_w_o
  Vec3 X_o;
  Vec3 X_c;
};

Scene random_scene(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  const Mat4 T_c_w = random_pose(20.0, 2.5, rng);
  const Mat4 T_w_o = random_pose(30.0, 2.5, rng);
  const Vec3 X_c(6 * u(rng), 2 * u(rng), 15 + 10 * u(rng));
  const Mat4 T_o_c = geometry::se3_inverse(T_c_w * T_w_o);
  return {params(T_c_w), params(T_w_o), transform(T_o_c, X_c), X_c};
}

// Measurement z = [u, v, u_right] (or [u, v]) of X_c, offset by `noise` px.
template <int kRows>
Eigen::Matrix<double, kRows, 1> observe(const geometry::StereoCamera& cam, const Vec3& X_c,
                                        double noise = 0.0) {
  Eigen::Matrix<double, kRows, 1> z;
  z.template head<2>() = cam.project(X_c);
  if constexpr (kRows == 3) z(2) = cam.project_right(X_c).x();
  return z + Eigen::Matrix<double, kRows, 1>::Constant(noise);
}

// Jacobians of every block against central differences, in the ambient coordinates and
// through the manifold's Plus; tolerance 1e-6 relative to the Jacobian's size.
template <int kRows>
void check_jacobians(const ceres::CostFunction& cost, Scene s) {
  using Residual = Eigen::Matrix<double, kRows, 1>;
  using PoseJac = Eigen::Matrix<double, kRows, kPoseSize, Eigen::RowMajor>;
  using PointJac = Eigen::Matrix<double, kRows, 3, Eigen::RowMajor>;
  std::array<double*, 3> x = {s.camera.data(), s.object.data(), s.X_o.data()};
  const std::array<int, 3> sizes = {kPoseSize, kPoseSize, 3};
  PoseJac Jc, Jo;
  PointJac Jp;
  double* jac[3] = {Jc.data(), Jo.data(), Jp.data()};
  Residual r0;
  ASSERT_TRUE(cost.Evaluate(x.data(), r0.data(), jac));
  auto residual = [&]() {
    Residual r;
    EXPECT_TRUE(cost.Evaluate(x.data(), r.data(), nullptr));
    return r;
  };
  const double h = 1e-6;
  for (int b = 0; b < 3; ++b) {
    Eigen::Map<const Eigen::Matrix<double, kRows, Eigen::Dynamic, Eigen::RowMajor>> J(
        jac[b], kRows, sizes[b]);
    const double tol = 1e-6 * J.norm();
    for (int i = 0; i < sizes[b]; ++i) {  // ambient
      const double saved = x[b][i];
      x[b][i] = saved + h;
      const Residual plus = residual();
      x[b][i] = saved - h;
      const Residual minus = residual();
      x[b][i] = saved;
      EXPECT_LT(((plus - minus) / (2 * h) - J.col(i)).norm(), tol)
          << "block " << b << " coord " << i;
    }
    if (b == 2) continue;
    PoseManifold manifold;
    Eigen::Matrix<double, kPoseSize, kPoseTangentSize, Eigen::RowMajor> P;
    ASSERT_TRUE(manifold.PlusJacobian(x[b], P.data()));
    const Eigen::Matrix<double, kRows, kPoseTangentSize> Jt = J * P;
    const Pose saved = b == 0 ? s.camera : s.object;
    for (int i = 0; i < kPoseTangentSize; ++i) {  // tangent
      double d[kPoseTangentSize] = {0, 0, 0, 0, 0, 0};
      d[i] = h;
      manifold.Plus(saved.data(), d, x[b]);
      const Residual plus = residual();
      d[i] = -h;
      manifold.Plus(saved.data(), d, x[b]);
      const Residual minus = residual();
      std::copy(saved.begin(), saved.end(), x[b]);
      EXPECT_LT(((plus - minus) / (2 * h) - Jt.col(i)).norm(), tol)
          << "block " << b << " tangent " << i;
    }
  }
}

}  // namespace

TEST(DynamicReprojection, JacobiansMatchNumericStereoAndMono) {
  const auto cam = test_scenes::kitti_camera();
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    SCOPED_TRACE(trial);
    const Scene s = random_scene(rng);
    const double inv_sigma2 = 1.0 / (1.2 * 1.2);
    StereoDynamicReprojectionCost stereo(&cam, observe<3>(cam, s.X_c, 0.7), inv_sigma2, 0.1);
    MonoDynamicReprojectionCost mono(&cam, observe<2>(cam, s.X_c, -0.4), inv_sigma2, 0.1);
    check_jacobians<3>(stereo, s);
    check_jacobians<2>(mono, s);
  }
}

TEST(DynamicReprojection, ResidualIsWeightedProjectionError) {
  const auto cam = test_scenes::kitti_camera();
  std::mt19937 rng(11);
  const Scene s = random_scene(rng);
  const double* x[3] = {s.camera.data(), s.object.data(), s.X_o.data()};
  const Vec3 z = observe<3>(cam, s.X_c);
  const Vec3 z_obs = z + Vec3(1.0, -2.0, 0.5);
  StereoDynamicReprojectionCost cost(&cam, z_obs, 0.25, 0.1);  // sigma = 2 px
  Vec3 r;
  ASSERT_TRUE(cost.Evaluate(x, r.data(), nullptr));
  EXPECT_LT((r - 0.5 * (z - z_obs)).norm(), 1e-9);
}

// With T_w_o = I, X_o is a world point: residual and tangent Jacobians equal e_stat's.
TEST(DynamicReprojection, EqualsStaticReprojectionForIdentityObject) {
  const auto cam = test_scenes::kitti_camera();
  std::mt19937 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    const Scene s0 = random_scene(rng);
    const Pose identity = params(Mat4::Identity());
    const Vec3 X_w = transform(params_to_pose(s0.object.data()), s0.X_o);
    const Vec3 z_obs = observe<3>(cam, s0.X_c, 0.3);
    StereoDynamicReprojectionCost dyna(&cam, z_obs, 0.7, 0.1);
    StereoReprojectionCost stat(&cam, z_obs, 0.7, 0.1);
    const double* xd[3] = {s0.camera.data(), identity.data(), X_w.data()};
    const double* xs[2] = {s0.camera.data(), X_w.data()};
    Eigen::Matrix<double, 3, 7, Eigen::RowMajor> Jcd, Jod, Jcs;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> Jpd, Jps;
    double* jd[3] = {Jcd.data(), Jod.data(), Jpd.data()};
    double* js[2] = {Jcs.data(), Jps.data()};
    Vec3 rd, rs;
    ASSERT_TRUE(dyna.Evaluate(xd, rd.data(), jd));
    ASSERT_TRUE(stat.Evaluate(xs, rs.data(), js));
    EXPECT_LT((rd - rs).norm(), 1e-9);
    EXPECT_LT((Jpd - Jps).norm(), 1e-9 * Jps.norm());
    PoseManifold manifold;
    Eigen::Matrix<double, 7, 6, Eigen::RowMajor> P;
    ASSERT_TRUE(manifold.PlusJacobian(s0.camera.data(), P.data()));
    EXPECT_LT((Jcd * P - Jcs * P).norm(), 1e-9 * (Jcs * P).norm());
  }
}

// A moving object seen by 3 fixed cameras: the poses of frames 1, 2 and the object points
// are recovered from perturbed starts with exact (stereo and mono) measurements.
TEST(DynamicReprojection, TinyBundleAdjustmentRecoversObjectPoses) {
  const auto cam = test_scenes::kitti_camera();
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Mat4> T_c_w, T_w_o;
  for (int k = 0; k < 3; ++k) {
    // the camera drives along +z; the car ahead drives faster and turns a little
    T_c_w.push_back(geometry::se3_inverse(geometry::make_pose(
        geometry::se3_exp((Vec6() << 0, 0, 0, 0, 0.01 * k, 0).finished()).topLeftCorner<3, 3>(),
        Vec3(0.1 * k, 0, 1.5 * k))));
    Vec6 xi;
    xi << 0.5 * k, 0.05 * k, 12.0 + 2.5 * k, 0.01 * k, 0.08 * k, 0.02 * k;
    T_w_o.push_back(geometry::se3_exp(xi));
  }
  std::vector<Vec3> X_o;  // points on a car-sized box
  for (int i = 0; i < 40; ++i) X_o.emplace_back(0.9 * u(rng), 0.75 * u(rng), 2.0 * u(rng));

  ProblemBuilder b;
  std::vector<int> cameras, objects, points;
  for (int k = 0; k < 3; ++k) cameras.push_back(b.add_pose(T_c_w[k], /*fixed=*/true));
  for (int k = 0; k < 3; ++k) {
    const Mat4 start = k == 0 ? T_w_o[k] : random_pose(0.3, 0.05, rng) * T_w_o[k];
    objects.push_back(b.add_pose(start, /*fixed=*/k == 0));
  }
  for (const Vec3& X : X_o) {
    points.push_back(b.add_point(X + 0.1 * Vec3(u(rng), u(rng), u(rng)), /*fixed=*/false));
  }
  for (int k = 0; k < 3; ++k) {
    for (size_t i = 0; i < X_o.size(); ++i) {
      const Vec3 X_c = transform(T_c_w[k] * T_w_o[k], X_o[i]);
      const bool stereo = i % 4 != 3;  // a quarter mono
      const double u_right = stereo ? cam.project_right(X_c).x() : -1.0;
      const auto id = b.add_dynamic_reprojection(cameras[k], objects[k], points[i], cam,
                                                 cam.project(X_c), u_right, 1.0, 2.45, 0.1);
      b.gate(id, 7.815);
    }
  }
  SolveOptions opt;
  opt.max_iterations = 50;
  opt.num_threads = 1;
  opt.function_tolerance = 1e-16;
  opt.gradient_tolerance = 1e-16;
  opt.parameter_tolerance = 1e-16;
  const SolveSummary summary = b.solve(opt);
  ASSERT_TRUE(summary.usable) << summary.message;
  EXPECT_GT(summary.initial_cost, 1.0);  // the start was really perturbed
  EXPECT_LT(summary.final_cost, 1e-12);
  EXPECT_EQ(b.remove_gated_outliers(), 0);
  for (int k = 0; k < 3; ++k) {
    const Mat4 T = b.pose(objects[k]);
    EXPECT_LT((T.topRightCorner<3, 1>() - T_w_o[k].topRightCorner<3, 1>()).norm(), 1e-6) << k;
    EXPECT_LT((T.topLeftCorner<3, 3>() - T_w_o[k].topLeftCorner<3, 3>()).norm(), 1e-6) << k;
  }
  for (size_t i = 0; i < X_o.size(); ++i) EXPECT_LT((b.point(points[i]) - X_o[i]).norm(), 1e-6);
}

// Behind the camera or closer than min_depth: evaluation fails as for e_stat, and the gate
// removes the residual.
TEST(DynamicReprojection, PointBehindCameraHandledLikeStatic) {
  const auto cam = test_scenes::kitti_camera();
  const Mat4 T_c_w = Mat4::Identity();
  const Mat4 T_w_o = geometry::make_pose(Mat3::Identity(), Vec3(0, 0, 10));
  ProblemBuilder b;
  const int c = b.add_pose(T_c_w, true);
  const int o = b.add_pose(T_w_o, false);
  const double min_depth = 0.1;
  int removed_expected = 0;
  for (double z_c : {-5.0, 0.05, 5.0}) {  // behind, inside min_depth, fine
    const Vec3 X_c(0.5, 0.2, z_c);
    const int p = b.add_point(X_c - Vec3(0, 0, 10), false);
    const int s = b.add_point(X_c, false);  // the same point as a static e_stat
    const Vec2 uv(600, 170);
    for (double u_right : {550.0, -1.0}) {
      const auto dyna =
          b.add_dynamic_reprojection(c, o, p, cam, uv, u_right, 1.0, 2.45, min_depth);
      const auto stat = b.add_stereo_reprojection(c, s, cam, uv, u_right, 1.0, 2.45, min_depth);
      double cost_d = 0, cost_s = 0;
      const bool ok_d = b.problem().EvaluateResidualBlock(dyna, false, &cost_d, nullptr, nullptr);
      const bool ok_s = b.problem().EvaluateResidualBlock(stat, false, &cost_s, nullptr, nullptr);
      EXPECT_EQ(ok_d, z_c > min_depth) << z_c;
      EXPECT_EQ(ok_d, ok_s) << z_c;
      if (ok_d) EXPECT_NEAR(cost_d, cost_s, 1e-9 * (1 + cost_s));
      b.gate(dyna, 1e12);  // only failures are removed
      if (!ok_d) ++removed_expected;
    }
  }
  EXPECT_EQ(removed_expected, 4);
  EXPECT_EQ(b.remove_gated_outliers(), removed_expected);
}

// The right image's principal point carries disparity_offset: the u_right row moves by it.
TEST(DynamicReprojection, DisparityOffsetHonoured) {
  auto cam = test_scenes::kitti_camera();
  std::mt19937 rng(9);
  const Scene s = random_scene(rng);
  const double* x[3] = {s.camera.data(), s.object.data(), s.X_o.data()};
  const Vec3 z_obs = observe<3>(cam, s.X_c);
  const double inv_sigma2 = 0.5;
  Vec3 r0, r1;
  StereoDynamicReprojectionCost cost(&cam, z_obs, inv_sigma2, 0.1);
  ASSERT_TRUE(cost.Evaluate(x, r0.data(), nullptr));
  EXPECT_LT(r0.norm(), 1e-9);
  cam.disparity_offset = 0.6;  // the cost reads the camera it points to
  ASSERT_TRUE(cost.Evaluate(x, r1.data(), nullptr));
  EXPECT_NEAR(r1(0), 0.0, 1e-9);
  EXPECT_NEAR(r1(1), 0.0, 1e-9);
  EXPECT_NEAR(r1(2), std::sqrt(inv_sigma2) * 0.6, 1e-9);
  // and a measurement taken with the offset is matched exactly
  StereoDynamicReprojectionCost matched(&cam, observe<3>(cam, s.X_c), inv_sigma2, 0.1);
  ASSERT_TRUE(matched.Evaluate(x, r1.data(), nullptr));
  EXPECT_LT(r1.norm(), 1e-9);
}

