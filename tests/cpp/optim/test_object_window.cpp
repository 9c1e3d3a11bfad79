// optimize_object_window (object_window.hpp): a car turning on a plane, seen by a noisy 3D
// detector with outliers and missed frames; the terms and their switches; degenerate input;
// the time of one call (printed, not asserted).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "optim/object_window.hpp"

using namespace twistslam;
using namespace twistslam::optim;

namespace {

const Vec3 kNormal(0, -1, 0);  // road plane normal in the camera frame (y points down)

// Ground truth: 1 m/frame (36 km/h at 10 Hz) turning at 0.04 rad/frame on the road plane,
// 1.6 m below the camera: T_i = exp(i xi) T_0 with a twist in the planar sub-space.
std::vector<Mat4> car_trajectory(int n) {
  const Mat4 T0 = geometry::make_pose(geometry::so3_exp(Vec3(0, 0.3, 0)), Vec3(-3, 1.6, 8));
  // Body velocity forward (+z of the object frame) and yaw rate, expressed in the world.
  const Mat3 R0 = T0.topLeftCorner<3, 3>();
  const Vec3 w(0, 0.04, 0);
  const Vec3 v = R0 * Vec3(0, 0, 1.0) - w.cross(T0.topRightCorner<3, 1>());
  Vec6 xi;
  xi << v, w;
  std::vector<Mat4> T;
  for (int i = 0; i < n; ++i) T.push_back(geometry::se3_exp(i * xi) * T0);
  return T;
}

double yaw_error(const Mat4& A, const Mat4& B) {  // rotation angle between, rad
  return geometry::so3_log(A.topLeftCorner<3, 3>().transpose() * B.topLeftCorner<3, 3>()).norm();
}

struct Rmse {
  double position = 0, yaw = 0;
};

Rmse rmse(const std::vector<Mat4>& est, const std::vector<Mat4>& truth,
          const std::vector<int>& frames) {
  Rmse r;
  for (int i : frames) {
    r.position += (est[i] - truth[i]).topRightCorner<3, 1>().squaredNorm();
    r.yaw += std::pow(yaw_error(est[i], truth[i]), 2);
  }
  r.position = std::sqrt(r.position / frames.size());
  r.yaw = std::sqrt(r.yaw / frames.size());
  return r;
}

// Detections: sigma 0.2 m per axis, 3 deg of yaw; frames `outliers` 2 m off, `missed` none.
// Initial values: the detection, or for a missed frame the constant-velocity prediction
// from the two previous initial values (what a tracker would hold).
std::vector<ObjectWindowFrame> detect(const std::vector<Mat4>& truth, std::mt19937& rng,
                                      const std::vector<int>& outliers,
                                      const std::vector<int>& missed) {
  std::normal_distribution<double> n(0, 1);
  std::vector<ObjectWindowFrame> frames(truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    auto& f = frames[i];
    const bool is_missed = std::count(missed.begin(), missed.end(), int(i)) > 0;
    const Vec3 dt = std::count(outliers.begin(), outliers.end(), int(i))
                        ? Vec3(2.0, 0, 0)
                        : Vec3(0.2 * n(rng), 0.2 * n(rng), 0.2 * n(rng));
    const Mat3 dR = geometry::so3_exp(kNormal * (3.0 * M_PI / 180.0) * n(rng));
    f.T_w_o_detected = geometry::make_pose(dR * truth[i].topLeftCorner<3, 3>(),
                                           truth[i].topRightCorner<3, 1>() + dt);
    f.has_detection = !is_missed;
    if (f.has_detection || i < 2) {
      f.T_w_o = f.T_w_o_detected;
    } else {
      f.T_w_o = geometry::se3_exp(geometry::twist_between(frames[i - 2].T_w_o,
                                                          frames[i - 1].T_w_o)) *
                frames[i - 1].T_w_o;
    }
  }
  return frames;
}

}  // namespace

TEST(ObjectWindow, BeatsRawDetectionsOnAPlanarTurn) {
  const int n = 15;
  const auto truth = car_trajectory(n);
  const Mat6 Pi = geometry::projector_planar(kNormal);
  const std::vector<int> outliers{4, 10}, missed{6, 7, 12};
  std::vector<int> detected, all;
  for (int i = 0; i < n; ++i) {
    all.push_back(i);
    if (std::count(missed.begin(), missed.end(), i) == 0) detected.push_back(i);
  }
  std::vector<int> inliers;  // detected frames with an inlier detection
  for (int i : detected) {
    if (std::count(outliers.begin(), outliers.end(), i) == 0) inliers.push_back(i);
  }
  Rmse raw_sum, raw_inlier_sum, opt_sum, opt_all_sum;
  const int trials = 20;
  for (int trial = 0; trial < trials; ++trial) {
    std::mt19937 rng(100 + trial);
    auto frames = detect(truth, rng, outliers, missed);
    std::vector<Mat4> raw;
    for (const auto& f : frames) raw.push_back(f.T_w_o_detected);
    const ObjectWindowSummary s = optimize_object_window(frames, Pi, ObjectWindowOptions{});
    ASSERT_TRUE(s.usable);
    EXPECT_LT(s.final_cost, s.initial_cost);
    std::vector<Mat4> est;
    for (const auto& f : frames) est.push_back(f.T_w_o);
    const Rmse r_raw = rmse(raw, truth, detected), r_opt = rmse(est, truth, detected);
    const Rmse r_all = rmse(est, truth, all);
    raw_sum.position += r_raw.position / trials, raw_sum.yaw += r_raw.yaw / trials;
    raw_inlier_sum.position += rmse(raw, truth, inliers).position / trials;
    opt_sum.position += r_opt.position / trials, opt_sum.yaw += r_opt.yaw / trials;
    opt_all_sum.position += r_all.position / trials, opt_all_sum.yaw += r_all.yaw / trials;
    // Every single window improves on its detections.
    EXPECT_LT(r_opt.position, 0.7 * r_raw.position) << "trial " << trial;
    EXPECT_LT(r_opt.yaw, r_raw.yaw) << "trial " << trial;
    EXPECT_GE(s.num_outliers, 2) << "trial " << trial;  // the two outliers' priors at least
    // The link keeps the refined motion on the plane: height along the road normal.
    for (int i = 1; i < n; ++i) {
      const Vec6 xi = geometry::twist_between(est[i - 1], est[i]);
      EXPECT_LT(((Mat6::Identity() - Pi) * xi).norm(), 0.02) << "trial " << trial;
    }
  }
  std::printf("[ position RMSE ] raw %.3f m (inliers %.3f m) -> optimised %.3f m (all frames %.3f m)\n",
              raw_sum.position, raw_inlier_sum.position, opt_sum.position, opt_all_sum.position);
  std::printf("[ yaw RMSE      ] raw %.2f deg -> optimised %.2f deg (all frames %.2f deg)\n",
              raw_sum.yaw * 180 / M_PI, opt_sum.yaw * 180 / M_PI, opt_all_sum.yaw * 180 / M_PI);
  // Averaged over the trials: well below the detections, and below their inliers alone (the
  // outliers were rejected, not just damped).
  EXPECT_LT(opt_sum.position, 0.4 * raw_sum.position);
  EXPECT_LT(opt_sum.position, 0.8 * raw_inlier_sum.position);
  EXPECT_LT(opt_sum.yaw, 0.75 * raw_sum.yaw);
}

// The same scene 100 m (and rotated) away from the world origin gives the same poses: the
// window is solved at its centroid, so W weighs the object's own motion, not the lever arm
// of a world origin wherever the map started.
TEST(ObjectWindow, ResultDoesNotDependOnTheWorldOrigin) {
  const auto truth = car_trajectory(12);
  std::mt19937 rng(17);
  const auto frames0 = detect(truth, rng, {5}, {8});
  const Mat4 S = geometry::make_pose(geometry::so3_exp(Vec3(0, 0.4, 0)), Vec3(100, 0, -60));
  auto a = frames0, b = frames0;
  for (auto& f : b) f.T_w_o = S * f.T_w_o, f.T_w_o_detected = S * f.T_w_o_detected;
  const Mat6 Pi = geometry::projector_planar(kNormal);
  // A rotation about the normal keeps the road plane: the projector is unchanged.
  ASSERT_TRUE(optimize_object_window(a, Pi, {}).usable);
  ASSERT_TRUE(optimize_object_window(b, Pi, {}).usable);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_LT((S * a[i].T_w_o - b[i].T_w_o).norm(), 1e-6) << "frame " << i;
  }
}

TEST(ObjectWindow, SwitchesRemoveTheirTerms) {
  const int n = 10;
  const auto truth = car_trajectory(n);
  const Mat6 Pi = geometry::projector_planar(kNormal);
  std::mt19937 rng(5);
  const auto frames0 = detect(truth, rng, {}, {3});  // 9 detections, 7 detected pairs
  auto count = [&](bool c, bool d, bool p, bool l) {
    ObjectWindowOptions o;
    o.use_const = c, o.use_det_twist = d, o.use_prior = p, o.use_link = l;
    auto frames = frames0;
    return optimize_object_window(frames, Pi, o).num_residuals;
  };
  EXPECT_EQ(count(true, true, true, true), 8 + 7 + 9 + 9);
  EXPECT_EQ(count(true, false, false, false), 8);
  EXPECT_EQ(count(false, true, false, false), 7);
  EXPECT_EQ(count(false, false, true, false), 9);
  EXPECT_EQ(count(false, false, false, true), 9);
  // A detection weight of 0 drops that frame's detection terms (prior and the one e_det).
  {
    auto frames = frames0;
    frames[2].detection_weight = 0;
    EXPECT_EQ(optimize_object_window(frames, Pi, {}).num_residuals, 8 + 6 + 8 + 9);
  }
  // Nothing at all: a no-op.
  auto frames = frames0;
  const auto s = optimize_object_window(frames, Pi, [] {
    ObjectWindowOptions o;
    o.use_const = o.use_det_twist = o.use_prior = o.use_link = false;
    return o;
  }());
  EXPECT_FALSE(s.usable);
  EXPECT_EQ(s.num_residuals, 0);
  for (int i = 0; i < n; ++i) EXPECT_EQ(frames[i].T_w_o, frames0[i].T_w_o);
  // Fixed frames keep their pose exactly, and terms among fixed frames only are left out.
  frames = frames0;
  frames[0].fixed = frames[1].fixed = true;
  const auto sf = optimize_object_window(frames, Pi, ObjectWindowOptions{});
  ASSERT_TRUE(sf.usable);
  EXPECT_EQ(sf.num_residuals, 8 + 6 + 7 + 8);
  EXPECT_EQ(frames[0].T_w_o, frames0[0].T_w_o);
  EXPECT_EQ(frames[1].T_w_o, frames0[1].T_w_o);
}

TEST(ObjectWindow, DegenerateInputIsANoOp) {
  const Mat6 Pi = geometry::projector_planar(kNormal);
  const auto truth = car_trajectory(4);
  std::mt19937 rng(9);
  // A single frame: nothing to do.
  std::vector<ObjectWindowFrame> one(1);
  one[0].T_w_o = truth[0];
  one[0].has_detection = true;
  one[0].T_w_o_detected = truth[1];
  EXPECT_FALSE(optimize_object_window(one, Pi, {}).usable);
  EXPECT_EQ(one[0].T_w_o, truth[0]);
  std::vector<ObjectWindowFrame> none;
  EXPECT_FALSE(optimize_object_window(none, Pi, {}).usable);

  // A NaN pose: usable = false, poses untouched.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto frames = detect(truth, rng, {}, {});
  frames[2].T_w_o(0, 3) = nan;
  const auto before = frames;
  EXPECT_FALSE(optimize_object_window(frames, Pi, {}).usable);
  for (size_t i = 0; i < frames.size(); ++i) {
    if (i != 2) EXPECT_EQ(frames[i].T_w_o, before[i].T_w_o);
  }
  // A NaN detection is treated as a missed one; a NaN projector is a no-op.
  frames = detect(truth, rng, {}, {});
  frames[1].T_w_o_detected(1, 1) = nan;
  const auto s = optimize_object_window(frames, Pi, {});
  EXPECT_TRUE(s.usable);
  EXPECT_EQ(s.num_residuals, 2 + 1 + 3 + 3);
  for (const auto& f : frames) EXPECT_TRUE(f.T_w_o.allFinite());
  Mat6 bad = Pi;
  bad(0, 0) = nan;
  EXPECT_FALSE(optimize_object_window(frames, bad, {}).usable);
  // A sigma <= 0 of a term in use is a configuration error.
  ObjectWindowOptions o;
  o.link_sigma_rotation = 0;
  EXPECT_THROW(optimize_object_window(frames, Pi, o), std::invalid_argument);
  o.use_link = false;
  EXPECT_NO_THROW(optimize_object_window(frames, Pi, o));
}

// The tracker calls this per track and per frame (~10 tracks, > 1000 frames/s): the median
// time of one call on a 10-frame window, printed for docs/optim.md, never asserted.
TEST(ObjectWindow, TimingOfOneCall) {
  const auto truth = car_trajectory(10);
  const Mat6 Pi = geometry::projector_planar(kNormal);
  for (bool with_detections : {true, false}) {
    std::mt19937 rng(21);
    std::vector<double> us;
    int iterations = 0;
    for (int rep = 0; rep < 300; ++rep) {
      auto frames = detect(truth, rng, {}, {});
      if (!with_detections) {  // e_const and e_link only; the first pose holds the gauge
        for (auto& f : frames) f.has_detection = false;
      }
      const auto t0 = std::chrono::steady_clock::now();
      const auto s = optimize_object_window(frames, Pi, {});
      const auto t1 = std::chrono::steady_clock::now();
      ASSERT_TRUE(s.usable);
      iterations += s.iterations;
      us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    }
    std::nth_element(us.begin(), us.begin() + us.size() / 2, us.end());
    std::printf("[ timing ] 10-frame window, %s: median %.1f us per call, %.1f iterations\n",
                with_detections ? "with detections" : "no detections", us[us.size() / 2],
                iterations / 300.0);
  }
}
