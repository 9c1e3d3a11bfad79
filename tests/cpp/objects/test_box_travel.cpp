// The travel of a track's box centres (objects/box_travel.hpp): a line through noisy centres
// gives the direction and distance driven, a wrong box far off the line does not turn it, a
// parked car travels ~nothing, and one frame gives no direction.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "objects/box_travel.hpp"

using namespace twistslam;
using namespace twistslam::objects;

TEST(BoxTravel, NoisyCentresGiveTheDirectionAndDistanceDriven) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.15);
  const Vec3 velocity(0.2, 0.0, -0.8);  // m/frame
  std::vector<BoxCentre> centres;
  for (int f = 10; f <= 20; ++f)
    centres.push_back({f, Vec3(3, 1.5, 40) + velocity * (f - 10) + Vec3(noise(rng), 0, noise(rng))});
  const BoxTravel t = box_travel(centres);
  ASSERT_TRUE(t.valid);
  EXPECT_EQ(t.inliers, 11);
  EXPECT_GT(t.velocity_w.normalized().dot(velocity.normalized()), 0.99);
  EXPECT_NEAR(t.distance_m, velocity.norm() * 10, 0.4);
}

TEST(BoxTravel, AWrongFirstBoxDoesNotTurnTheDirection) {
  // an oncoming car moving slowly towards the camera (-z); its first box is another car's,
  // 2.5 m off against the motion: first-to-last would say the car drove away (+z)
  const Vec3 velocity(0, 0, -0.15);
  std::vector<BoxCentre> centres{{0, Vec3(0, 1.5, 40 - 2.5)}};
  for (int f = 1; f <= 12; ++f) centres.push_back({f, Vec3(0, 1.5, 40) + velocity * f});
  ASSERT_GT((centres.back().centre_w - centres.front().centre_w).z(), 0);  // the naive answer
  const BoxTravel t = box_travel(centres);
  ASSERT_TRUE(t.valid);
  EXPECT_EQ(t.inliers, 12);
  EXPECT_LT(t.velocity_w.z(), 0);
  EXPECT_NEAR(t.distance_m, 0.15 * 11, 0.05);
}

TEST(BoxTravel, AParkedCarTravelsNothingAndOneFrameIsNoDirection) {
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<BoxCentre> parked;
  for (int f = 0; f < 30; ++f) parked.push_back({f, Vec3(5 + noise(rng), 1.5, 20 + noise(rng))});
  const BoxTravel t = box_travel(parked);
  ASSERT_TRUE(t.valid);
  EXPECT_LT(t.distance_m, 0.5);  // well below heading_from_motion_m (1.5 m)

  EXPECT_FALSE(box_travel({{4, Vec3(1, 2, 3)}}).valid);
  EXPECT_FALSE(box_travel({{4, Vec3(1, 2, 3)}, {4, Vec3(1, 2, 5)}}).valid);  // one frame twice
  EXPECT_FALSE(box_travel({}).valid);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(box_travel({{1, Vec3(nan, 0, 0)}, {2, Vec3(1, 0, 0)}}).valid);  // NaN left out
}

TEST(BoxTravel, TheDistancesStandardErrorTellsScatterFromTravel) {
  // a far car's boxes (55 m) scatter by ~0.6 m a frame: a parked car or one creeping
  // 0.04 m/frame seems to travel metres, but not by five standard errors (and never the wrong
  // way by many); a car driving 0.5 m/frame does
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.6);
  int apparent = 0, parked_significant = 0, creeping_backwards = 0, driving_significant = 0;
  constexpr int kTrials = 500;
  auto significant = [](const BoxTravel& t) { return t.distance_m > 5 * t.distance_sigma_m; };
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<BoxCentre> parked, creeping, driving;
    for (int f = 0; f < 12; ++f) {
      const Vec3 start(12, 1.6, 55);
      parked.push_back({f, start + Vec3(noise(rng), 0, noise(rng))});
      creeping.push_back({f, start + Vec3(-0.04 * f + noise(rng), 0, noise(rng))});
      driving.push_back({f, start + Vec3(-0.5 * f + noise(rng), 0, noise(rng))});
    }
    const BoxTravel p = box_travel(parked), c = box_travel(creeping), d = box_travel(driving);
    ASSERT_TRUE(p.valid && c.valid && d.valid);
    apparent += p.distance_m > 1.5;
    parked_significant += significant(p);
    creeping_backwards += significant(c) && c.velocity_w.x() > 0;
    driving_significant += significant(d) && d.velocity_w.x() < 0;
  }
  EXPECT_GT(apparent, kTrials / 20);  // the distance alone is fooled, often
  EXPECT_LE(parked_significant, 2);
  EXPECT_LE(creeping_backwards, 1);
  EXPECT_GE(driving_significant, kTrials * 90 / 100);
  // too few boxes to tell their scatter
  const BoxTravel three = box_travel({{0, Vec3(0, 0, 0)}, {1, Vec3(1, 0, 0)}, {2, Vec3(2.1, 0, 0)}});
  ASSERT_TRUE(three.valid);
  EXPECT_TRUE(std::isinf(three.distance_sigma_m));
}
