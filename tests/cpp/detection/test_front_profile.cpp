// Front and back of a car from the height profile of its returns (front_profile.hpp): a car
// whose greenhouse sits behind its middle gets the yaw of its front at any heading; a box
// with a flat top (no greenhouse), or a profile with too few returns, stays undecided.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "detection/detector.hpp"
#include "detection/front_profile.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::detection;
using namespace twistslam::test_scenes;

namespace {
constexpr double kDeg = M_PI / 180.0;
constexpr double kYawTolerance = 3.0 * kDeg;  // the L-shape fit's 1 deg step, noiseless faces

// |a - b| modulo 2 pi, in [0, pi]: a box turned around is pi off
double yaw_error(double a, double b) {
  const double e = std::fmod(std::abs(a - b), 2.0 * M_PI);
  return std::min(e, 2.0 * M_PI - e);
}

// A sedan of two boxes facing `yaw` (KITTI rotation_y): a 4.4 m body 0.95 m high and, on top
// of it, a 2.2 m greenhouse 0.5 m high whose centre lies 0.45 m behind the body's (a 1.55 m
// hood ahead of it, a 0.65 m trunk behind it).
std::vector<SceneBox> sedan(double x, double z, double yaw) {
  SceneBox body, greenhouse;
  body.x = x, body.z = z, body.yaw = yaw;
  body.length = 4.4, body.width = 1.75, body.height = 0.95;
  greenhouse = body;
  const double back = -0.45;  // m along the heading (cos yaw, -sin yaw) in (x, z)
  greenhouse.x = x + back * std::cos(yaw);
  greenhouse.z = z - back * std::sin(yaw);
  greenhouse.length = 2.2, greenhouse.width = 1.45, greenhouse.height = 0.5, greenhouse.lift = 0.95;
  return {body, greenhouse};
}

std::vector<ProfilePoint> profile(double hood_m, double trunk_m, int per_metre) {
  // returns along a 4.4 m car centred at 0, front at +x: body 0.3-0.9 m high everywhere,
  // greenhouse 1.1-1.45 m between the hood's and the trunk's ends
  std::vector<ProfilePoint> points;
  for (int i = 0; i <= 44 * per_metre / 10; ++i) {
    const float along = static_cast<float>(-2.2 + 4.4 * i / (44 * per_metre / 10));
    points.push_back({along, 0.3f});
    points.push_back({along, 0.9f});
    if (along < 2.2 - hood_m && along > -2.2 + trunk_m) points.push_back({along, 1.45f});
  }
  return points;
}
}  // namespace

TEST(FrontProfile, TheLongerLidBeforeTheGreenhouseIsTheHood) {
  const DetectorOptions o;
  EXPECT_EQ(front_from_profile(profile(1.5, 0.6, 20), o), +1);
  EXPECT_EQ(front_from_profile(profile(0.6, 1.5, 20), o), -1);
  // a hood and trunk within front_profile_min_gap_difference_m of each other: undecided
  EXPECT_EQ(front_from_profile(profile(1.1, 0.9, 20), o), 0);
  // a flat top (a box, a van seen from the side with no greenhouse step): undecided
  EXPECT_EQ(front_from_profile(profile(0.0, 0.0, 20), o), 0);
  // too few returns to span the car
  EXPECT_EQ(front_from_profile(profile(1.5, 0.6, 2), o), 0);
  EXPECT_EQ(front_from_profile({}, o), 0);
}

TEST(FrontProfile, AHiddenEndDecidesOnlyForItself) {
  // a car at (6, 16) along z (yaw -pi/2: heading +z, its +x end the far one, at the lower
  // azimuth); the far end's azimuth side is hidden. Its hood there lost 0.9 m of lid to what
  // hides it: the profile reads the near end as the front, which the rule refuses; a profile
  // that still puts the front at the hidden end decides.
  Detection car;
  car.centre = Vec3(6.0, 0.9, 16.0);
  car.yaw = -0.5 * M_PI;
  car.length = 4.4;
  car.length_seen = true;
  ClusterShape shape;
  shape.hidden_low_azimuth = true;  // the far (+x) end's side: atan2(x, z) falls with z
  const DetectorOptions o;
  Detection hood_cut = car;
  tell_front(hood_cut, shape, profile(0.6, 1.5, 20), o);  // reads: front at -x (near end)
  EXPECT_FALSE(hood_cut.heading_known);
  EXPECT_DOUBLE_EQ(hood_cut.yaw, car.yaw);
  Detection hood_seen = car;
  tell_front(hood_seen, shape, profile(1.5, 0.6, 20), o);  // front at +x, the hidden end
  EXPECT_TRUE(hood_seen.heading_known);
  EXPECT_DOUBLE_EQ(hood_seen.yaw, car.yaw);
  // the near end hidden instead: the near-end reading decides, and turns the yaw around
  shape.hidden_low_azimuth = false;
  shape.hidden_high_azimuth = true;
  Detection near_front = car;
  tell_front(near_front, shape, profile(0.6, 1.5, 20), o);
  EXPECT_TRUE(near_front.heading_known);
  EXPECT_NEAR(near_front.yaw, 0.5 * M_PI, 1e-12);
  // both sides hidden, or a length the prior set: nothing is told
  shape.hidden_low_azimuth = true;
  Detection both = car;
  tell_front(both, shape, profile(1.5, 0.6, 20), o);
  EXPECT_FALSE(both.heading_known);
  Detection prior_length = car;
  prior_length.length_seen = false;
  tell_front(prior_length, ClusterShape{}, profile(1.5, 0.6, 20), o);
  EXPECT_FALSE(prior_length.heading_known);
}

TEST(FrontProfile, ASedanSeenFromTheSideGetsTheYawOfItsFront) {
  int whole_length_views = 0;
  for (const double yaw_deg : {0.0, 30.0, 90.0, 150.0, 180.0, -120.0, -60.0}) {
    for (const double x : {-6.0, 5.0}) {
      const double yaw = yaw_deg * kDeg;
      const DetectorResult r = detect(cast_scene(sedan(x, 16.0, yaw)));
      SCOPED_TRACE("yaw " + std::to_string(yaw_deg) + " x " + std::to_string(x));
      ASSERT_EQ(r.detections.size(), 1u);
      const Detection& d = r.detections[0];
      if (!d.length_seen) continue;  // a view along the car: only its rear (or front) is seen
      ++whole_length_views;
      EXPECT_TRUE(d.heading_known);
      EXPECT_LT(yaw_error(d.yaw, yaw), kYawTolerance);
      EXPECT_GE(d.yaw, -M_PI);
      EXPECT_LT(d.yaw, M_PI);
    }
  }
  EXPECT_GE(whole_length_views, 10);  // of 14: the views along the car (yaw 90 deg) are not
}

TEST(FrontProfile, OffOrFlatTheYawStaysModPi) {
  DetectorOptions off;
  off.front_from_profile = false;
  const double yaw = 150.0 * kDeg;
  const DetectorResult r = detect(cast_scene(sedan(5.0, 16.0, yaw)), off);
  ASSERT_EQ(r.detections.size(), 1u);
  EXPECT_FALSE(r.detections[0].heading_known);
  EXPECT_GE(r.detections[0].yaw, -0.5 * M_PI);
  EXPECT_LT(r.detections[0].yaw, 0.5 * M_PI);
  SceneBox box;  // one box: its top is flat, nothing tells its ends apart
  box.x = 5.0, box.z = 16.0, box.yaw = yaw, box.length = 4.4, box.height = 1.45;
  const DetectorResult flat = detect(cast_scene({box}));
  ASSERT_EQ(flat.detections.size(), 1u);
  EXPECT_TRUE(flat.detections[0].length_seen);
  EXPECT_FALSE(flat.detections[0].heading_known);
}

// The signed gap difference behind front_from_profile: hood minus trunk, NaN when a profile is
// too sparse to tell (a track averages its views' differences, front_from_views).
TEST(FrontProfile, TheGapDifferenceIsHoodMinusTrunkOrNaN) {
  // the returns lie 0.05 m apart: each end of the greenhouse is placed to within a step
  EXPECT_NEAR(profile_gap_difference(profile(1.5, 0.6, 20), 0.8), 0.9, 0.1);
  EXPECT_NEAR(profile_gap_difference(profile(0.6, 1.5, 20), 0.8), -0.9, 0.1);
  EXPECT_NEAR(profile_gap_difference(profile(1.0, 0.8, 20), 0.8), 0.2, 0.1);  // below 0.4 m
  EXPECT_EQ(front_from_profile(profile(1.0, 0.8, 20), DetectorOptions()), 0);
  EXPECT_TRUE(std::isnan(profile_gap_difference(profile(1.5, 0.6, 2), 0.8)));  // 27 returns
}

// Several views: a clear mean decides where no single view would; too few views, a mean
// within the scatter or below the floor, and NaN views do not count.
TEST(FrontProfile, ViewsDecideByTheirMeanAgainstItsStandardError) {
  const std::vector<double> car21 = {0.28, 0.47, 0.28, 0.03, 0.29, 0.09, 0.27};  // urban s13
  EXPECT_EQ(front_from_views(car21, 5, 3.0, 0.1), +1);
  std::vector<double> turned;
  for (const double d : car21) turned.push_back(-d);
  EXPECT_EQ(front_from_views(turned, 5, 3.0, 0.1), -1);
  EXPECT_EQ(front_from_views(car21, 8, 3.0, 0.1), 0);                        // 7 views only
  EXPECT_EQ(front_from_views(car21, 5, 3.0, 0.3), 0);                        // mean 0.24 m
  EXPECT_EQ(front_from_views({0.4, -0.3, 0.35, -0.25, 0.3, -0.2}, 5, 3.0, 0.0), 0);  // scatter
  std::vector<double> with_nan = {NAN, NAN, 0.28, 0.47, 0.28, 0.29};
  EXPECT_EQ(front_from_views(with_nan, 5, 3.0, 0.1), 0);  // 4 finite views
  with_nan.push_back(0.27);
  EXPECT_EQ(front_from_views(with_nan, 5, 3.0, 0.1), +1);
}
