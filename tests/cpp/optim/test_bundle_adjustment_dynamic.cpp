// e_dyna and the link in the local BA (paper eq. 9): a car driving ahead of the cameras of a
// synthetic street, its keypoints reprojected through its pose at each keyframe; and its
// LiDAR terms (e_det / e_reg, the box prior) relative to those cameras.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <memory>
#include <stdexcept>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "optim/ba_object_costs.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::optim;
using namespace twistslam::optim::testing;

namespace {

constexpr int kKeyframes = 6, kFixed = 2;

// The car at keyframe k: 10 m ahead of the camera's start, driving along +z at 1.8 m per
// keyframe while turning slowly about the road normal (y): planar motion.
Mat4 car_pose(int k) {
  const double yaw = 0.02 * k;
  Mat3 R;
  R << std::cos(yaw), 0, std::sin(yaw), 0, 1, 0, -std::sin(yaw), 0, std::cos(yaw);
  return geometry::make_pose(R, Vec3(1.5 + 0.1 * k, 0.8, 10.0 + 1.8 * k));
}

// Camera centre height (world y) error of keyframe k.
double height_error(const BAProblem& p, const BAProblem& truth, int k) {
  const Vec3 c = geometry::se3_inverse(p.keyframes[k].T_c_w).topRightCorner<3, 1>();
  const Vec3 c_true = geometry::se3_inverse(truth.keyframes[k].T_c_w).topRightCorner<3, 1>();
  return std::abs(c.y() - c_true.y());
}

struct Scene {
  BAProblem truth, problem;
};

// Few far static points (mono, 30-60 m) and the car's 40 stereo points; the free keyframes
// start 0.3 m too high, the car's poses 0.1 m too high and 0.2 m off in the road plane.
Scene make_scene(unsigned seed, Mat4 (*pose_of)(int) = car_pose, const int* frames = nullptr) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const auto cam = kitti_camera();
  Scene s;
  for (int k = 0; k < kKeyframes; ++k) s.truth.keyframes.push_back({street_pose(k), k < kFixed});
  while (s.truth.points.size() < 12) {
    const Vec3 X = street_point(rng, 30, 60);
    std::vector<BAObservation> obs;
    for (int k = 0; k < kKeyframes; ++k) {
      Keypoint kp;
      const Mat4& T = s.truth.keyframes[k].T_c_w;
      if (observe(cam, T.topLeftCorner<3, 3>() * X + T.topRightCorner<3, 1>(), false, rng, &kp))
        obs.push_back({k, static_cast<int>(s.truth.points.size()), kp.uv, kp.u_right, kp.inv_sigma2});
    }
    if (obs.size() < kKeyframes) continue;
    s.truth.points.push_back({X, false});
    s.truth.observations.insert(s.truth.observations.end(), obs.begin(), obs.end());
  }
  BAObject car;
  car.Pi = geometry::projector_planar(Vec3(0, -1, 0));
  for (int k = 0; k < kKeyframes; ++k) car.poses.push_back({k, pose_of(k), false, frames ? frames[k] : -1});
  while (car.points_o.size() < 40) {  // on the car's back and side: a 4 x 1.5 x 1.8 m box
    const Vec3 X_o(-2 + 4 * u(rng), -0.75 + 1.5 * u(rng), u(rng) < 0.5 ? -0.9 : -2 + 4 * u(rng));
    const int j = static_cast<int>(car.points_o.size());
    car.points_o.push_back(X_o);
    for (int k = 0; k < kKeyframes; ++k) {
      const Mat4 T_c_o = s.truth.keyframes[k].T_c_w * car.poses[k].T_w_o;
      Keypoint kp;
      if (observe(cam, T_c_o.topLeftCorner<3, 3>() * X_o + T_c_o.topRightCorner<3, 1>(), true, rng, &kp))
        s.truth.dynamic_observations.push_back({0, k, j, kp.uv, kp.u_right, kp.inv_sigma2});
    }
  }
  s.truth.objects.push_back(car);
  s.problem = s.truth;
  for (int k = kFixed; k < kKeyframes; ++k)  // T_c_w of a camera 0.3 m higher (y down)
    s.problem.keyframes[k].T_c_w.topRightCorner<3, 1>() -=
        s.problem.keyframes[k].T_c_w.topLeftCorner<3, 3>() * Vec3(0, -0.3, 0);
  for (auto& pose : s.problem.objects[0].poses)
    pose.T_w_o.topRightCorner<3, 1>() += Vec3(0.2 * u(rng), -0.1, 0.2 * u(rng));
  return s;
}

}  // namespace

TEST(BundleAdjustmentDynamic, TheLinkedCarInformsTheCameraHeight) {
  const auto cam = kitti_camera();
  Scene with = make_scene(5);
  Scene without = with;
  without.problem.objects.clear();
  without.problem.dynamic_observations.clear();
  const auto r_with = bundle_adjust(with.problem, cam);
  const auto r_without = bundle_adjust(without.problem, cam);
  ASSERT_TRUE(r_with.converged && r_without.converged);
  EXPECT_EQ(r_with.num_dynamic_residuals, static_cast<int>(with.truth.dynamic_observations.size()));
  EXPECT_EQ(r_without.num_dynamic_residuals, 0);
  double e_with = 0, e_without = 0;
  for (int k = kFixed; k < kKeyframes; ++k) {
    e_with += height_error(with.problem, with.truth, k) / (kKeyframes - kFixed);
    e_without += height_error(without.problem, without.truth, k) / (kKeyframes - kFixed);
  }
  std::printf("[ info ] camera height error %.3f m with the car, %.3f m without\n", e_with, e_without);
  EXPECT_LT(e_with, 0.05);
  EXPECT_LT(e_with, 0.5 * e_without);
  // the car follows: its points in the world (the object frame's origin is a gauge that
  // X_o and T_w_o trade) back at the true height at every keyframe
  const BAObject& car = with.problem.objects[0];
  const BAObject& car_true = with.truth.objects[0];
  for (int k = 0; k < kKeyframes; ++k) {
    double dy = 0;
    for (size_t j = 0; j < car.points_o.size(); ++j)
      dy += ((car.poses[k].T_w_o * car.points_o[j].homogeneous()) -
             (car_true.poses[k].T_w_o * car_true.points_o[j].homogeneous())).y() / car.points_o.size();
    EXPECT_LT(std::abs(dy), 0.05) << "keyframe " << k;
  }
  int flagged = 0;
  for (auto o : r_with.dynamic_outlier) flagged += o;
  EXPECT_LT(flagged, 0.05 * r_with.dynamic_outlier.size());
}

TEST(BundleAdjustmentDynamic, AWrongMatchOnTheCarIsFlagged) {
  const auto cam = kitti_camera();
  Scene s = make_scene(6);
  auto& bad = s.problem.dynamic_observations[7];
  bad.uv += Vec2(25, -18);
  const auto r = bundle_adjust(s.problem, cam);
  ASSERT_TRUE(r.converged);
  ASSERT_EQ(r.dynamic_outlier.size(), s.problem.dynamic_observations.size());
  EXPECT_EQ(r.dynamic_outlier[7], 1);
}

TEST(BundleAdjustmentDynamic, AnObjectSeenFromOneKeyframeIsLeftOut) {
  const auto cam = kitti_camera();
  Scene s = make_scene(7);
  BAProblem one = s.problem;
  auto& obs = one.dynamic_observations;
  obs.erase(std::remove_if(obs.begin(), obs.end(), [](const auto& o) { return o.pose != 3; }), obs.end());
  BAProblem none = s.problem;
  none.objects.clear();
  none.dynamic_observations.clear();
  const auto r_one = bundle_adjust(one, cam);
  const auto r_none = bundle_adjust(none, cam);
  EXPECT_EQ(r_one.num_dynamic_residuals, 0);
  // the same problem as without the object, up to the summation order of Ceres' two
  // threads (the last bits differ from run to run)
  for (int k = 0; k < kKeyframes; ++k)
    EXPECT_TRUE(one.keyframes[k].T_c_w.isApprox(none.keyframes[k].T_c_w, 1e-9)) << "keyframe " << k;
  EXPECT_EQ(one.objects[0].poses[3].T_w_o, s.problem.objects[0].poses[3].T_w_o);  // untouched
}

TEST(BundleAdjustmentDynamic, IndicesOutOfRangeThrowNamingTheField) {
  const auto cam = kitti_camera();
  Scene s = make_scene(8);
  auto expect_throw = [&](BAProblem p, const std::string& field) {
    try {
      bundle_adjust(p, cam);
      ADD_FAILURE() << "no exception for " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  BAProblem p = s.problem;
  p.dynamic_observations[0].object = 3;
  expect_throw(p, "object index");
  p = s.problem;
  p.dynamic_observations[1].pose = kKeyframes;
  expect_throw(p, "pose index");
  p = s.problem;
  p.dynamic_observations[2].point = -1;
  expect_throw(p, "point index");
  p = s.problem;
  p.objects[0].poses[2].keyframe = 99;
  expect_throw(p, "pose keyframe");
}

TEST(BundleAdjustmentDynamic, NaNObjectPoseIsSkippedNotFatal) {
  const auto cam = kitti_camera();
  Scene s = make_scene(9);
  s.problem.objects[0].poses[4].T_w_o(0, 3) = std::numeric_limits<double>::quiet_NaN();
  const auto r = bundle_adjust(s.problem, cam);
  ASSERT_TRUE(r.converged);
  for (size_t e = 0; e < s.problem.dynamic_observations.size(); ++e)
    if (s.problem.dynamic_observations[e].pose == 4) EXPECT_EQ(r.dynamic_outlier[e], 1);
  for (const auto& kf : s.problem.keyframes) EXPECT_TRUE(kf.T_c_w.allFinite());
}

// --- the LiDAR terms (e_det / e_reg and the box prior, relative to the cameras) ---------------

namespace {

// D of poses a and b from the truth: the object's motion from camera a's frame to camera b's.
Mat4 camera_relative_motion(const BAProblem& truth, int a, int b) {
  const BAObject& car = truth.objects[0];
  const Mat4 T_ca_o = truth.keyframes[a].T_c_w * car.poses[a].T_w_o;
  const Mat4 T_cb_o = truth.keyframes[b].T_c_w * car.poses[b].T_w_o;
  return T_cb_o * geometry::se3_inverse(T_ca_o);
}

// The car of the problem keeps its first n points and their observations only.
void keep_car_points(Scene* s, int n) {
  s->problem.objects[0].points_o.resize(n);
  auto& obs = s->problem.dynamic_observations;
  obs.erase(std::remove_if(obs.begin(), obs.end(), [n](const auto& o) { return o.point >= n; }),
            obs.end());
}

// The pose blocks [t, q] of T.
std::array<double, 7> block(const Mat4& T) {
  const Eigen::Quaterniond q(Mat3(T.topLeftCorner<3, 3>()));
  return {T(0, 3), T(1, 3), T(2, 3), q.x(), q.y(), q.z(), q.w()};
}

}  // namespace

TEST(BundleAdjustmentDynamic, CameraRelativeLidarTermsVanishAtTheTruthOnly) {
  Scene s = make_scene(10);
  const BAProblem& t = s.truth;
  const Mat6 Pi = t.objects[0].Pi;
  const Vec3 c = t.objects[0].poses[1].T_w_o.topRightCorner<3, 1>();
  std::unique_ptr<ceres::CostFunction> motion(detail::make_camera_relative_motion_cost(
      Pi, camera_relative_motion(t, 1, 4), c, 0.01, 0.001));
  std::unique_ptr<ceres::CostFunction> box(detail::make_camera_relative_box_cost(
      t.keyframes[4].T_c_w * t.objects[0].poses[4].T_w_o, 0.01, 0.001));
  auto cam_a = block(t.keyframes[1].T_c_w), cam_b = block(t.keyframes[4].T_c_w);
  auto obj_a = block(t.objects[0].poses[1].T_w_o), obj_b = block(t.objects[0].poses[4].T_w_o);
  auto evaluate = [&](ceres::CostFunction* f, std::vector<const double*> blocks) {
    Vec6 r;
    EXPECT_TRUE(f->Evaluate(blocks.data(), r.data(), nullptr));
    return r;
  };
  EXPECT_LT(evaluate(motion.get(), {cam_a.data(), cam_b.data(), obj_a.data(), obj_b.data()}).norm(), 1e-6);
  EXPECT_LT(evaluate(box.get(), {cam_b.data(), obj_b.data()}).norm(), 1e-6);
  // the object 5 cm further along the road at b: 5 sigmas of translation, in the link's plane
  auto moved = obj_b;
  moved[2] += 0.05;
  const Vec6 r_motion = evaluate(motion.get(), {cam_a.data(), cam_b.data(), obj_a.data(), moved.data()});
  EXPECT_NEAR(r_motion.head<3>().norm(), 5.0, 0.05);
  EXPECT_LT(r_motion.tail<3>().norm(), 1e-6);
  EXPECT_NEAR(evaluate(box.get(), {cam_b.data(), moved.data()}).head<3>().norm(), 5.0, 1e-6);
  // the camera b moved with the object: the same camera-relative pose, the same box residual
  // (zero), but a world motion the measurement does not explain
  const Mat4 shift = geometry::make_pose(Mat3::Identity(), Vec3(0, 0, 0.05));
  auto cam_b_moved = block(t.keyframes[4].T_c_w * geometry::se3_inverse(shift));
  EXPECT_LT(evaluate(box.get(), {cam_b_moved.data(), moved.data()}).norm(), 1e-6);
  EXPECT_LT(evaluate(motion.get(), {cam_a.data(), cam_b_moved.data(), obj_a.data(), moved.data()}).norm(), 1e-6);
}

TEST(BundleAdjustmentDynamic, BoxesPlaceTheObjectFrame) {
  // e_dyna alone leaves the object frame a gauge (T_w_o G with G^-1 X_o fits the same
  // keypoints): the poses stay about where they started. Its boxes put it where they are,
  // relative to the cameras (this street's far mono points let the cameras themselves drift
  // along the road, and the object with them: both are compared as T_c_o).
  const auto cam = kitti_camera();
  Scene with = make_scene(11);
  Scene without = with;
  for (int k = 0; k < kKeyframes; ++k)
    with.problem.objects[0].boxes.push_back(
        {k, with.truth.keyframes[k].T_c_w * with.truth.objects[0].poses[k].T_w_o, 0.02, 0.005, 0});
  const auto r_with = bundle_adjust(with.problem, cam);
  const auto r_without = bundle_adjust(without.problem, cam);
  ASSERT_TRUE(r_with.converged && r_without.converged);
  EXPECT_EQ(r_with.num_object_boxes, kKeyframes);
  EXPECT_EQ(r_without.num_object_boxes, 0);
  auto T_c_o = [](const BAProblem& p, int k) { return p.keyframes[k].T_c_w * p.objects[0].poses[k].T_w_o; };
  double e_with = 0, e_without = 0;
  for (int k = 0; k < kKeyframes; ++k) {
    e_with = std::max(e_with, translation_error(T_c_o(with.problem, k), T_c_o(with.truth, k)));
    e_without += translation_error(T_c_o(without.problem, k), T_c_o(with.truth, k)) / kKeyframes;
  }
  std::printf("[ info ] object pose error in the camera: %.3f m (worst) with boxes, %.3f m (mean) "
              "without\n", e_with, e_without);
  EXPECT_LT(e_with, 0.05);
  EXPECT_GT(e_without, 0.08);
}

TEST(BundleAdjustmentDynamic, RegisteredMotionsSteadyAnObjectWithFewPoints) {
  // eight stereo points on the car: its poses follow their noise; the measured motions
  // between consecutive keyframes (as GICP would give them, exact here) hold them together
  const auto cam = kitti_camera();
  double e_with = 0, e_without = 0;
  int motions = 0;
  for (unsigned seed = 20; seed < 26; ++seed) {
    Scene with = make_scene(seed);
    keep_car_points(&with, 8);
    BAObject& car = with.problem.objects[0];
    Scene without = with;
    for (int k = 0; k + 1 < kKeyframes; ++k)
      car.motions.push_back({k, k + 1, camera_relative_motion(with.truth, k, k + 1), 0.01, 0.001, 0});
    const auto r_with = bundle_adjust(with.problem, cam);
    const auto r_without = bundle_adjust(without.problem, cam);
    ASSERT_TRUE(r_with.converged && r_without.converged);
    motions += r_with.num_object_motions;
    // the motion between two keyframes as the cameras see it (D), against the truth's
    for (int k = 0; k + 1 < kKeyframes; ++k) {
      const Mat4 truth = camera_relative_motion(with.truth, k, k + 1);
      e_with += translation_error(camera_relative_motion(with.problem, k, k + 1), truth);
      e_without += translation_error(camera_relative_motion(without.problem, k, k + 1), truth);
    }
  }
  std::printf("[ info ] keyframe-to-keyframe object motion error: %.4f m with, %.4f m without\n",
              e_with / (6 * (kKeyframes - 1)), e_without / (6 * (kKeyframes - 1)));
  EXPECT_EQ(motions, 6 * (kKeyframes - 1));
  EXPECT_LT(e_with, 0.5 * e_without);
}

TEST(BundleAdjustmentDynamic, LidarTermIndicesOutOfRangeThrow) {
  const auto cam = kitti_camera();
  Scene s = make_scene(12);
  BAProblem p = s.problem;
  p.objects[0].motions.push_back({0, kKeyframes, Mat4::Identity(), 0.1, 0.01, 0});
  EXPECT_THROW(bundle_adjust(p, cam), std::invalid_argument);
  p = s.problem;
  p.objects[0].boxes.push_back({-1, Mat4::Identity(), 0.1, 0.01, 0});
  EXPECT_THROW(bundle_adjust(p, cam), std::invalid_argument);
  // a non-rigid measurement is left out, not fatal
  p = s.problem;
  Mat4 bad = Mat4::Identity();
  bad(0, 0) = 3;
  p.objects[0].motions.push_back({0, 1, bad, 0.1, 0.01, 0});
  const auto r = bundle_adjust(p, cam);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.num_object_motions, 0);
}

namespace {

// Keyframes some frames apart, and a car at a constant world twist per frame (a gentle left
// curve at 0.6 m per frame): T(f) = exp(f xi) T(0), so e_const's per-frame twists agree.
constexpr int kFrames[kKeyframes] = {0, 3, 5, 9, 12, 14};

Mat4 constant_twist_car(int k) {
  Vec6 xi;
  xi << 0.01, 0, 0.6, 0, 0.006, 0;
  return geometry::se3_exp(kFrames[k] * xi) * car_pose(0);
}

}  // namespace

TEST(BundleAdjustmentDynamic, KeyframeConstVelocityVanishesAtAConstantTwistOnly) {
  const Mat6 Pi = geometry::projector_planar(Vec3(0, -1, 0));
  std::unique_ptr<ceres::CostFunction> f(detail::make_keyframe_constant_velocity_cost(
      Pi, kFrames[2] - kFrames[1], kFrames[3] - kFrames[2],
      constant_twist_car(2).topRightCorner<3, 1>(), 0.01, 0.001));
  auto a = block(constant_twist_car(1)), b = block(constant_twist_car(2)), c = block(constant_twist_car(3));
  Vec6 r;
  std::vector<const double*> blocks{a.data(), b.data(), c.data()};
  ASSERT_TRUE(f->Evaluate(blocks.data(), r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-6);
  b[2] += 0.05;  // the middle pose 5 cm further along: the two mean twists disagree
  ASSERT_TRUE(f->Evaluate(blocks.data(), r.data(), nullptr));
  // 0.05 / 2 frames faster, then 0.05 / 4 frames slower: 3.75 cm/frame, 3.75 sigmas
  EXPECT_NEAR(r.head<3>().norm(), 3.75, 0.05);
  EXPECT_THROW(detail::make_keyframe_constant_velocity_cost(Pi, 0, 2, Vec3::Zero(), 0.01, 0.001),
               std::invalid_argument);
}

TEST(BundleAdjustmentDynamic, KeyframeConstVelocitySteadiesAnObjectWithFewPoints) {
  const auto cam = kitti_camera();
  double e_with = 0, e_without = 0;
  int terms = 0;
  for (unsigned seed = 30; seed < 36; ++seed) {
    Scene with = make_scene(seed, constant_twist_car, kFrames);
    keep_car_points(&with, 8);
    BAObject& car = with.problem.objects[0];
    Scene without = with;
    car.const_sigma_translation = 0.01;
    car.const_sigma_rotation = 0.001;
    const auto r_with = bundle_adjust(with.problem, cam);
    const auto r_without = bundle_adjust(without.problem, cam);
    ASSERT_TRUE(r_with.converged && r_without.converged);
    terms += r_with.num_object_const;
    EXPECT_EQ(r_without.num_object_const, 0);
    for (int k = 0; k + 1 < kKeyframes; ++k) {
      const Mat4 truth = camera_relative_motion(with.truth, k, k + 1);
      e_with += translation_error(camera_relative_motion(with.problem, k, k + 1), truth);
      e_without += translation_error(camera_relative_motion(without.problem, k, k + 1), truth);
    }
  }
  std::printf("[ info ] keyframe-to-keyframe object motion error: %.4f m with e_const, %.4f m "
              "without\n", e_with / (6 * (kKeyframes - 1)), e_without / (6 * (kKeyframes - 1)));
  EXPECT_EQ(terms, 6 * (kKeyframes - 2));
  EXPECT_LT(e_with, 0.7 * e_without);
}
