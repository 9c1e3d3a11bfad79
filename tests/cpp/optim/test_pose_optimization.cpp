// Pose-only optimisation (paper eq. 3) on synthetic KITTI-like observations.
#include <gtest/gtest.h>

#include <chrono>
#include <limits>

#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::optim;
using namespace twistslam::optim::testing;

namespace {

struct PoseScene {
  Mat4 T_true;
  std::vector<StereoObservation> obs;
  std::vector<bool> is_outlier;
};

PoseScene make_scene(int n, double outlier_ratio, bool stereo, unsigned seed) {
  std::mt19937 rng(seed);
  const auto cam = kitti_camera();
  PoseScene s;
  s.T_true = street_pose(7);
  const Mat4 T_w_c = geometry::se3_inverse(s.T_true);
  std::uniform_real_distribution<double> u(0, 1);
  while (static_cast<int>(s.obs.size()) < n) {
    // Points drawn in the camera frame, then moved to the world.
    const Vec3 X_c = street_point(rng, 3, 60);
    Keypoint kp;
    if (!observe(cam, X_c, stereo, rng, &kp)) continue;
    const bool outlier = u(rng) < outlier_ratio;
    if (outlier) kp = gross_outlier(cam, stereo, rng);
    StereoObservation o;
    o.point_w = T_w_c.topLeftCorner<3, 3>() * X_c + T_w_c.topRightCorner<3, 1>();
    o.uv = kp.uv;
    o.u_right = kp.u_right;
    o.inv_sigma2 = kp.inv_sigma2;
    s.obs.push_back(o);
    s.is_outlier.push_back(outlier);
  }
  return s;
}

void expect_recovered(const PoseScene& s, const PoseOptimizationResult& r, double max_t,
                      double max_deg) {
  ASSERT_TRUE(r.converged);
  EXPECT_LT(translation_error(r.T_c_w, s.T_true), max_t);
  EXPECT_LT(rotation_error_deg(r.T_c_w, s.T_true), max_deg);
  int outliers = 0, caught = 0, inliers = 0, lost = 0;
  for (size_t i = 0; i < s.obs.size(); ++i) {
    if (s.is_outlier[i]) {
      ++outliers;
      caught += !r.inlier[i];
    } else {
      ++inliers;
      lost += !r.inlier[i];
    }
  }
  EXPECT_GT(caught, 0.95 * outliers) << caught << " / " << outliers << " outliers flagged";
  EXPECT_LT(lost, 0.10 * inliers) << lost << " / " << inliers << " inliers flagged";
  int n = 0;
  for (auto f : r.inlier) n += f;
  EXPECT_EQ(n, r.num_inliers);
}

}  // namespace

TEST(PoseOptimization, StereoConvergesWithThirtyPercentOutliers) {
  const auto cam = kitti_camera();
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const PoseScene s = make_scene(600, 0.3, true, seed);
    std::mt19937 rng(100 + seed);
    const Mat4 T0 = perturb(s.T_true, 0.5, 5.0 * M_PI / 180, rng);
    ASSERT_GT(rotation_error_deg(T0, s.T_true), 4.9);
    const auto r = optimize_pose(T0, s.obs, cam);
    SCOPED_TRACE("seed " + std::to_string(seed));
    expect_recovered(s, r, 0.02, 0.1);
  }
}

TEST(PoseOptimization, MonoOnlyConverges) {
  const auto cam = kitti_camera();
  for (unsigned seed = 11; seed <= 13; ++seed) {
    const PoseScene s = make_scene(600, 0.3, false, seed);
    std::mt19937 rng(100 + seed);
    const Mat4 T0 = perturb(s.T_true, 0.5, 5.0 * M_PI / 180, rng);
    const auto r = optimize_pose(T0, s.obs, cam);
    SCOPED_TRACE("seed " + std::to_string(seed));
    // Mono constrains depth through parallax only: looser translation bound.
    expect_recovered(s, r, 0.05, 0.1);
  }
}

TEST(PoseOptimization, MixedStereoAndMono) {
  const auto cam = kitti_camera();
  PoseScene s = make_scene(600, 0.2, true, 21);
  for (size_t i = 0; i < s.obs.size(); i += 2) s.obs[i].u_right = -1;  // half mono
  std::mt19937 rng(7);
  const auto r = optimize_pose(perturb(s.T_true, 0.3, 3.0 * M_PI / 180, rng), s.obs, cam);
  expect_recovered(s, r, 0.02, 0.1);
}

TEST(PoseOptimization, OneRoundWithoutRejectionIsWorse) {
  // The rounds matter: a single round keeps the outliers (they only get Huber weights).
  const auto cam = kitti_camera();
  const PoseScene s = make_scene(600, 0.3, true, 3);
  std::mt19937 rng(9);
  const Mat4 T0 = perturb(s.T_true, 0.5, 5.0 * M_PI / 180, rng);
  PoseOptimizationOptions one;
  one.rounds = 1;
  const auto r1 = optimize_pose(T0, s.obs, cam, one);
  const auto r4 = optimize_pose(T0, s.obs, cam);
  EXPECT_LT(translation_error(r4.T_c_w, s.T_true), translation_error(r1.T_c_w, s.T_true));
}

TEST(PoseOptimization, EmptyObservations) {
  const auto cam = kitti_camera();
  const Mat4 T0 = street_pose(3);
  const auto r = optimize_pose(T0, {}, cam);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.num_inliers, 0);
  EXPECT_TRUE(r.inlier.empty());
  EXPECT_EQ(r.T_c_w, T0);
}

TEST(PoseOptimization, NaNInputs) {
  const auto cam = kitti_camera();
  PoseScene s = make_scene(200, 0.0, true, 5);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.obs[0].point_w.x() = nan;
  s.obs[1].uv.y() = nan;
  s.obs[2].inv_sigma2 = 0;
  s.obs[3].u_right = nan;
  std::mt19937 rng(3);
  const auto r = optimize_pose(perturb(s.T_true, 0.1, 0.01, rng), s.obs, cam);
  ASSERT_TRUE(r.converged);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r.inlier[i], 0) << i;
  EXPECT_LT(translation_error(r.T_c_w, s.T_true), 0.02);

  Mat4 bad = s.T_true;
  bad(0, 3) = nan;
  const auto rb = optimize_pose(bad, s.obs, cam);
  EXPECT_FALSE(rb.converged);
  EXPECT_TRUE(std::isnan(rb.T_c_w(0, 3)));  // the initial pose, as given
  Mat4 skewed = s.T_true;
  skewed(0, 1) += 0.3;  // not a rotation
  EXPECT_FALSE(optimize_pose(skewed, s.obs, cam).converged);
}

TEST(PoseOptimization, AllPointsBehindCamera) {
  const auto cam = kitti_camera();
  PoseScene s = make_scene(100, 0.0, true, 6);
  // Flip the camera around: every point is now behind it.
  Mat4 flip = Mat4::Identity();
  flip(0, 0) = -1;
  flip(2, 2) = -1;
  const Mat4 T0 = flip * s.T_true;
  const auto r = optimize_pose(T0, s.obs, cam);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.num_inliers, 0);
  EXPECT_EQ(r.T_c_w, T0);
}

TEST(PoseOptimization, TooFewInliersIsNotConverged) {
  const auto cam = kitti_camera();
  const PoseScene s = make_scene(8, 0.0, true, 8);
  const auto r = optimize_pose(s.T_true, s.obs, cam);  // 8 < min_inliers = 10
  EXPECT_FALSE(r.converged);
  PoseOptimizationOptions o;
  o.min_inliers = 5;
  EXPECT_TRUE(optimize_pose(s.T_true, s.obs, cam, o).converged);
}

TEST(PoseOptimization, TimingIsReported) {
  const auto cam = kitti_camera();
  const PoseScene s = make_scene(600, 0.2, true, 31);
  std::mt19937 rng(1);
  const Mat4 T0 = perturb(s.T_true, 0.1, 0.02, rng);
  const auto t0 = std::chrono::steady_clock::now();
  const int reps = 50;
  for (int i = 0; i < reps; ++i) optimize_pose(T0, s.obs, cam);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[ timing ] optimize_pose, 600 observations: %.3f ms\n", ms / reps);
}
