// The travel axis of a vehicle learned from its steps (objects/travel_direction.hpp): noisy
// steps along a direction give that axis, reversing keeps it, steps out of the road plane are
// projected onto it, and nothing is returned before min_path_m, for steps in every direction, or
// for steps that cancel out (a crawling far car's depth jitter).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "objects/travel_direction.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {

constexpr double kDeg = M_PI / 180.0;
const Vec3 kUp(0, -1, 0);

double axis_angle_deg(const Vec3& a, const Vec3& b) {  // sign-free
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) / kDeg;
}

TEST(TravelDirection, NoisyStepsGiveTheirAxisAndReversingKeepsIt) {
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0, 0.03);
  const Vec3 dir = Vec3(0.3, 0, 1).normalized();
  TravelDirection t;
  for (int i = 0; i < 20; ++i) {
    const double speed = i < 12 ? 0.8 : -0.5;  // drives, then reverses
    t.add_step(speed * dir + Vec3(noise(rng), noise(rng), noise(rng)), kUp);
  }
  const Vec3 axis = t.axis(3.0, 10.0);
  ASSERT_NEAR(axis.norm(), 1.0, 1e-9);
  EXPECT_LT(axis_angle_deg(axis, dir), 2.0);
  EXPECT_NEAR(axis.dot(kUp), 0.0, 1e-9);  // in the road plane
  EXPECT_NEAR(t.path_m, 12 * 0.8 + 8 * 0.5, 0.5);
}

TEST(TravelDirection, StepsOutOfThePlaneAreProjectedOntoIt) {
  TravelDirection t;
  for (int i = 0; i < 10; ++i) t.add_step(Vec3(0, 0.5, 1.0), kUp);  // climbing along the normal
  EXPECT_LT(axis_angle_deg(t.axis(3.0, 10.0), Vec3(0, 0, 1)), 1e-6);
  EXPECT_NEAR(t.path_m, 10.0, 1e-9);  // the plane's share of each step only
}

TEST(TravelDirection, UnknownBeforeTheMinimumPathOrWithoutADirection) {
  TravelDirection t;
  t.add_step(Vec3(0, 0, 1.0), kUp);
  t.add_step(Vec3(0, 0, 1.0), kUp);
  EXPECT_EQ(t.axis(3.0, 10.0), Vec3::Zero());  // 2 m < 3 m
  t.add_step(Vec3(0, 0, 1.5), kUp);
  EXPECT_GT(t.axis(3.0, 10.0).norm(), 0.5);
  TravelDirection wander;  // a parked car's jitter: steps in every direction
  for (int i = 0; i < 40; ++i) {
    const double a = i * 2.4;
    wander.add_step(0.2 * Vec3(std::cos(a), 0, std::sin(a)), kUp);
  }
  EXPECT_EQ(wander.axis(3.0, 10.0), Vec3::Zero());
  TravelDirection bad;
  bad.add_step(Vec3(NAN, 0, 1), kUp);  // ignored, not a NaN axis
  bad.add_step(Vec3(0, 0, 5), Vec3::Zero());
  EXPECT_EQ(bad.path_m, 0.0);
  EXPECT_EQ(bad.axis(0.0, 1.0), Vec3::Zero());
}

TEST(TravelDirection, JitterAlongTheLineOfSightGivesNoAxisWhereItCancelsOut) {
  // urban s8's car 32 at 40-47 m: it crawls 0.065 m/frame along x (its heading) while its
  // far stereo swings its estimate back and forth along the line of sight (z), 1-2 m each way.
  // The steps' moments point along z, as anisotropic as a drive: only the net displacement
  // tells the two apart
  TravelDirection t;
  double z_prev = 0;
  for (int i = 1; i <= 50; ++i) {
    const double z = 1.5 * std::sin(2 * M_PI * i / 25.0);  // two swings of +-1.5 m
    t.add_step(Vec3(0.065, 0, z - z_prev), kUp);
    z_prev = z;
  }
  ASSERT_GT(t.path_m, 3.0);
  EXPECT_LT(axis_angle_deg(t.axis(3.0, 10.0), Vec3(0, 0, 1)), 20.0);  // the jitter's axis...
  EXPECT_LT(t.net_o.norm(), 0.5 * t.path_m);
  EXPECT_EQ(t.axis(3.0, 10.0, 0.5), Vec3::Zero());  // ... is not taken for the travel
  EXPECT_NEAR(t.net_o.x(), 50 * 0.065, 1e-9);
}

TEST(TravelDirection, ADriveKeepsItsAxisUnlessItComesMostOfTheWayBack) {
  TravelDirection drive, back;
  for (int i = 0; i < 20; ++i) {
    drive.add_step(Vec3(0, 0, i < 16 ? 0.8 : -0.5), kUp);  // 12.8 m on, 2 m back
    back.add_step(Vec3(0, 0, i < 10 ? 0.8 : -0.6), kUp);    // 8 m on, 6 m back
  }
  EXPECT_LT(axis_angle_deg(drive.axis(3.0, 10.0, 0.5), Vec3(0, 0, 1)), 1e-6);
  EXPECT_GT(back.axis(3.0, 10.0, 0.0).norm(), 0.5);
  EXPECT_EQ(back.axis(3.0, 10.0, 0.5), Vec3::Zero());  // 2 m net of 14 m: no e_head
}

TEST(TravelDirection, RotatingTheObjectFrameTurnsTheNetDisplacementToo) {
  TravelDirection t;
  for (int i = 0; i < 10; ++i) t.add_step(Vec3(0.5, 0, 0), kUp);
  const Mat3 R = Eigen::AngleAxisd(30 * kDeg, kUp).toRotationMatrix();  // R_old_new
  t.rotate(R);
  EXPECT_LT((t.net_o - R.transpose() * Vec3(5, 0, 0)).norm(), 1e-9);
  EXPECT_LT(axis_angle_deg(t.axis(3.0, 10.0, 0.9), R.transpose() * Vec3(1, 0, 0)), 1e-6);
}

}  // namespace
