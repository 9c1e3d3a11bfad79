// The pose of a frame from descriptor matches alone (tracking/descriptor_pose.hpp): map points
// with random descriptors seen from a camera 1.2 m ahead (a frame of driving at 43 km/h, where
// the no-motion prediction is off by the whole step), among keypoints of unrelated texture.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "common/kitti_camera.hpp"
#include "geometry/se3.hpp"
#include "tracking/descriptor_pose.hpp"

using namespace twistslam;

namespace {

const geometry::StereoCamera kCamera = test_scenes::kitti_camera();

map::Descriptor random_descriptor(std::mt19937& rng) {
  map::Descriptor d;
  std::uniform_int_distribution<int> byte(0, 255);
  for (auto& b : d) b = static_cast<std::uint8_t>(byte(rng));
  return d;
}

// A copy of d with `bits` bits flipped (a re-detected keypoint's descriptor).
map::Descriptor flipped(map::Descriptor d, int bits, std::mt19937& rng) {
  std::uniform_int_distribution<int> bit(0, 8 * static_cast<int>(d.size()) - 1);
  for (int k = 0; k < bits; ++k) {
    const int b = bit(rng);
    d[b / 8] ^= static_cast<std::uint8_t>(1u << (b % 8));
  }
  return d;
}

struct Scene {
  map::Map map;
  std::vector<int> point_ids;
  tracking::Frame frame;
  Mat4 T_c_w = Mat4::Identity();
};

// 150 map points 4-60 m deep seen from the world origin; the frame is 1.2 m ahead and turned
// 1 deg, its keypoints the points' projections (0.5 px noise, 8 bits of descriptor noise) for
// the `seen` fraction of them, `wrong` of those with another point's pixel, plus 300 keypoints
// of unrelated texture.
Scene make_scene(std::mt19937& rng, double seen, double wrong) {
  Scene s;
  Vec6 xi;
  xi << 0, 0, 1.2, 0, M_PI / 180.0, 0;
  s.T_c_w = geometry::se3_inverse(geometry::se3_exp(xi));
  std::uniform_real_distribution<double> u(0, kCamera.width), v(0, kCamera.height), unit(0, 1);
  std::normal_distribution<double> pixel_noise(0, 0.5);
  std::vector<Vec2> pixels;
  std::vector<map::Descriptor> descriptors;
  while (s.point_ids.size() < 150) {
    const Vec3 X_w = kCamera.backproject(Vec2(u(rng), v(rng)), 4 + 56 * unit(rng));
    const Vec3 X_c = s.T_c_w.topLeftCorner<3, 3>() * X_w + s.T_c_w.topRightCorner<3, 1>();
    const Vec2 uv = kCamera.project(X_c);
    if (X_c.z() < 1 || !kCamera.in_image(uv, 10)) continue;
    const map::Descriptor d = random_descriptor(rng);
    s.point_ids.push_back(s.map.add_point(X_w, d, 0).id);
    if (unit(rng) < seen) pixels.push_back(uv), descriptors.push_back(flipped(d, 8, rng));
  }
  const size_t num_wrong = static_cast<size_t>(wrong * static_cast<double>(pixels.size()));
  std::shuffle(pixels.begin(), pixels.begin() + static_cast<long>(num_wrong), rng);
  for (int k = 0; k < 300; ++k)
    pixels.emplace_back(u(rng), v(rng)), descriptors.push_back(random_descriptor(rng));
  map::StereoKeypoints& kp = s.frame.keypoints;
  for (size_t i = 0; i < pixels.size(); ++i) {
    kp.uv.push_back(pixels[i] + Vec2(pixel_noise(rng), pixel_noise(rng)));
    kp.octave.push_back(0);
    kp.u_right.push_back(-1);
    kp.depth.push_back(-1);
    kp.descriptors.push_back(descriptors[i]);
    kp.label.push_back(-1);
  }
  return s;
}

}  // namespace

TEST(DescriptorPose, RecoversAWholeFrameOfDrivingWithoutAPrior) {
  std::mt19937 rng(7);
  const Scene s = make_scene(rng, 0.8, 0.2);  // 20 % of the seen points matched to wrong pixels
  const auto pose = tracking::pose_from_descriptors(s.frame, s.map, s.point_ids, kCamera, {});
  ASSERT_TRUE(pose.has_value());
  const Mat4 err = geometry::se3_inverse(s.T_c_w) * pose->T_c_w;
  const double shift_m = err.topRightCorner<3, 1>().norm();
  EXPECT_LT(shift_m, 0.05);
  const double angle = std::acos(std::min(1.0, (err.topLeftCorner<3, 3>().trace() - 1) / 2));
  EXPECT_LT(angle, 0.2 * M_PI / 180);
  EXPECT_GE(pose->inliers, 60);
  EXPECT_LE(pose->inliers, pose->matches);
}

TEST(DescriptorPose, TooFewMatchesGiveNoPose) {
  std::mt19937 rng(8);
  const Scene s = make_scene(rng, 0.06, 0.0);  // ~9 points seen: fewer than min_inliers (20)
  EXPECT_FALSE(tracking::pose_from_descriptors(s.frame, s.map, s.point_ids, kCamera, {}).has_value());
  // no points at all, or points the map does not hold
  EXPECT_FALSE(tracking::pose_from_descriptors(s.frame, s.map, {}, kCamera, {}).has_value());
  EXPECT_FALSE(tracking::pose_from_descriptors(s.frame, s.map, {100000, 100001}, kCamera, {}).has_value());
}
