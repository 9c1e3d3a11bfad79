// Road plane from the road cluster: a sloped noisy road with clutter, the prior fallback (too
// few points, too steep), re-fitting as points arrive, the bounded deterministic reservoir.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "objects/road_plane.hpp"

using namespace twistslam;
using namespace twistslam::objects;

namespace {

constexpr double kDeg = M_PI / 180.0;
const Vec3 kPriorUp(0, -1, 0);

double angle_deg(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) / kDeg;
}

// count points on the plane n_up . X + d = 0 (x in [-8, 8] m, z in [3, 40] m) with noise_m along
// the normal; a fraction of them replaced by clutter above the road (cars, poles, mislabels).
Points3 road_points(const Vec3& n_up, double d, int count, double clutter, unsigned seed,
                    double noise_m = 0.03) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, noise_m);
  const Vec3 n = n_up.normalized();
  Points3 P(count, 3);
  for (int i = 0; i < count; ++i) {
    const double x = -8 + 16 * u(rng), z = 3 + 37 * u(rng);
    if (u(rng) < clutter) {
      P.row(i) = Vec3(x, -3 + 4.5 * u(rng), z).transpose();
      continue;
    }
    const double y = -(n.x() * x + n.z() * z + d) / n.y();
    P.row(i) = (Vec3(x, y, z) + noise(rng) * n).transpose();
  }
  return P;
}

const Vec3 kSlopedUp = Vec3(0.03, -1, 0.06).normalized();  // 6 % grade, 3 % cross slope

}  // namespace

TEST(RoadPlane, SlopedNoisyRoadWithClutter) {
  RoadPlaneEstimator road;
  road.add_points(road_points(kSlopedUp, 1.65, 3000, 0.3, 1));
  ASSERT_TRUE(road.valid());
  EXPECT_LT(angle_deg(road.normal_up(), kSlopedUp), 0.3);
  EXPECT_GT(road.normal_up().dot(kPriorUp), 0.0);  // oriented up
  EXPECT_NEAR(road.plane()(3), 1.65, 0.05);
  EXPECT_NEAR(road.normal_up().norm(), 1.0, 1e-12);
}

TEST(RoadPlane, FallsBackToThePrior) {
  RoadPlaneEstimator road;
  EXPECT_FALSE(road.valid());
  EXPECT_EQ(road.normal_up(), kPriorUp);
  road.add_points(road_points(kSlopedUp, 1.65, 20, 0.0, 2));  // below min_points
  EXPECT_FALSE(road.valid());
  EXPECT_EQ(road.num_fits(), 0);
  EXPECT_EQ(road.normal_up(), kPriorUp);
  EXPECT_EQ(road.plane()(3), 1.65);

  RoadPlaneEstimator steep;  // a 30 deg "road" (a wall or a ramp mislabelled) is refused
  const Vec3 tilted = Vec3(0, -std::cos(30 * kDeg), std::sin(30 * kDeg));
  steep.add_points(road_points(tilted, 1.65, 1000, 0.0, 3));
  EXPECT_EQ(steep.num_fits(), 1);
  EXPECT_FALSE(steep.valid());
  EXPECT_EQ(steep.normal_up(), kPriorUp);

  RoadPlaneEstimator clutter;  // nothing but clutter: too few inliers
  clutter.add_points(road_points(kSlopedUp, 1.65, 500, 1.0, 4));
  EXPECT_FALSE(clutter.valid());

  RoadPlaneOptions bad;
  bad.max_points = 0;
  EXPECT_THROW(RoadPlaneEstimator{bad}, std::invalid_argument);
}

TEST(RoadPlane, RefitsAsTheMapGrows) {
  RoadPlaneEstimator road;  // refit_growth 0.2
  road.add_points(road_points(kPriorUp, 1.65, 1000, 0.2, 5));
  EXPECT_EQ(road.num_fits(), 1);
  EXPECT_LT(angle_deg(road.normal_up(), kPriorUp), 0.5);
  road.add_points(road_points(kSlopedUp, 1.65, 100, 0.0, 6));  // +10 %: not yet
  EXPECT_EQ(road.num_fits(), 1);
  road.add_points(road_points(kSlopedUp, 1.65, 150, 0.0, 7));  // +25 % in all: re-fit
  EXPECT_EQ(road.num_fits(), 2);
  // The map moves on to a sloped stretch: the reservoir follows and the plane with it.
  for (unsigned k = 0; k < 20; ++k) road.add_points(road_points(kSlopedUp, 1.65, 2000, 0.0, 10 + k));
  EXPECT_EQ(road.num_points(), 5000);
  EXPECT_EQ(road.points_seen(), 41250);
  EXPECT_TRUE(road.valid());
  EXPECT_LT(angle_deg(road.normal_up(), kSlopedUp), 0.3);
}

TEST(RoadPlane, DeterministicAndSkipsNonFinite) {
  RoadPlaneEstimator a, b;
  Points3 P = road_points(kSlopedUp, 1.65, 8000, 0.3, 8);
  P(5, 1) = NAN;
  a.add_points(P);
  b.add_points(P);
  EXPECT_EQ(a.points_seen(), 7999);
  EXPECT_EQ(a.plane(), b.plane());
  EXPECT_TRUE(a.valid());
}

TEST(RoadPlane, AWindowFollowsAGradeChangeTheWholeMapLagsBehind) {
  // 20 keyframes 1 m apart on level road, then 6 on a 6 % grade: the camera is on the grade now
  RoadPlaneOptions windowed;
  windowed.window_m = 4.5;  // the last 5 keyframes
  RoadPlaneEstimator recent(windowed), whole;
  unsigned seed = 100;
  double z = 0;
  for (int k = 0; k < 20; ++k, z += 1) {
    const Points3 P = road_points(kPriorUp, 1.65, 400, 0.1, seed++);
    recent.add_points(P, Vec3(0, 0, z));
    whole.add_points(P, Vec3(0, 0, z));
  }
  EXPECT_LT(angle_deg(recent.normal_up(), kPriorUp), 0.3);
  const Vec3 grade_up = Vec3(0, -1, 0.06).normalized();
  for (int k = 0; k < 6; ++k, z += 1) {
    const Points3 P = road_points(grade_up, 1.65, 400, 0.1, seed++);
    recent.add_points(P, Vec3(0, 0, z));
    whole.add_points(P, Vec3(0, 0, z));
  }
  ASSERT_TRUE(recent.valid());
  EXPECT_LT(angle_deg(recent.normal_up(), grade_up), 0.3);
  EXPECT_NEAR(recent.plane()(3), 1.65, 0.05);
  // the reservoir over every point seen still holds mostly level road
  EXPECT_GT(angle_deg(whole.normal_up(), grade_up), 2.0);
  // the window re-fits on every keyframe, on the last 5 keyframes' points only
  EXPECT_EQ(recent.num_fits(), 26);
  EXPECT_EQ(recent.num_points(), 5 * 400);
  EXPECT_EQ(recent.points_seen(), 26 * 400);
}

TEST(RoadPlane, AWindowKeepsTheNewestPointsUpToItsCapacityAndSkipsNonFinite) {
  RoadPlaneOptions o;
  o.window_m = 100;
  o.max_points = 1000;
  RoadPlaneEstimator road(o);
  road.add_points(road_points(kPriorUp, 1.65, 800, 0.0, 200), Vec3(0, 0, 0));
  EXPECT_EQ(road.num_points(), 800);
  Points3 sloped = road_points(kSlopedUp, 1.65, 1200, 0.0, 201);  // more than the capacity
  sloped(3, 0) = NAN;
  road.add_points(sloped, Vec3(0, 0, 1));
  EXPECT_EQ(road.points_seen(), 800 + 1199);
  EXPECT_EQ(road.num_points(), 1000);  // the newest batch alone fills it
  ASSERT_TRUE(road.valid());
  EXPECT_LT(angle_deg(road.normal_up(), kSlopedUp), 0.3);
  // a batch too small to fit alone, 300 m on: the window drops the rest, the last fit stays
  road.add_points(road_points(kSlopedUp, 1.65, 10, 0.0, 202), Vec3(0, 0, 301));
  EXPECT_EQ(road.num_points(), 10);
  EXPECT_TRUE(road.valid());
  EXPECT_LT(angle_deg(road.normal_up(), kSlopedUp), 0.3);
  EXPECT_THROW(road.add_points(road_points(kSlopedUp, 1.65, 10, 0.0, 203), Vec3(0, NAN, 0)),
               std::invalid_argument);
  RoadPlaneOptions bad;
  bad.window_m = -1;
  EXPECT_THROW(RoadPlaneEstimator{bad}, std::invalid_argument);
}
