// Surface roughness (surface_roughness.hpp): flat and car-like surfaces measure near 0,
// scattered returns high, the voxel thinning makes the measure independent of the sampling
// density, and the detector drops a car-sized hedge (a leaf layer that its faces' fit
// accepts) by it while the car beside it stays.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "detection/detector.hpp"
#include "detection/surface_roughness.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::detection;
using namespace twistslam::test_scenes;

namespace {

// ScenePoints (x, up, z) and the indices of all of them.
struct Cloud {
  std::vector<ScenePoint> points;
  std::vector<int> members;
  void add(double x, double up, double z) {
    members.push_back(static_cast<int>(points.size()));
    points.push_back({static_cast<float>(x), static_cast<float>(z), static_cast<float>(up),
                      static_cast<int>(points.size())});
  }
};

// A car's side and roof sampled every `step` m, with `noise_m` Gaussian range noise.
Cloud car_surface(double step, double noise_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  Cloud c;
  for (double s = 0; s <= 4.0; s += step) {
    for (double up = 0.3; up <= 1.0; up += step) c.add(noise(rng), up, 10.0 + s);  // side
    for (double w = 0; w <= 1.7; w += step) c.add(w, 1.45 + noise(rng), 10.0 + s);   // roof
  }
  return c;
}

}  // namespace

TEST(SurfaceRoughness, SmoothSurfacesAreNearZeroAndScatterIsHigh) {
  const Cloud flat = car_surface(0.05, 0.0, 1);
  const SurfaceRoughness f = surface_roughness(flat.members, flat.points, 0.1, 10);
  EXPECT_GT(f.num_points, 300);
  EXPECT_LT(f.median_variation, 0.01);

  // LiDAR-like 1 cm range noise leaves a car's faces smooth at the 0.1 m voxel's scale
  const Cloud car = car_surface(0.05, 0.01, 2);
  EXPECT_LT(surface_roughness(car.members, car.points, 0.1, 10).median_variation, 0.03);

  // returns anywhere in a 2 x 1.5 x 3 m volume: foliage
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud leaves;
  for (int i = 0; i < 2000; ++i) leaves.add(2.0 * u(rng), 1.5 * u(rng), 10.0 + 3.0 * u(rng));
  // (isotropic scatter is 1/3 in the limit; 10-point covariances bias the smallest axis low)
  EXPECT_GT(surface_roughness(leaves.members, leaves.points, 0.1, 10).median_variation, 0.1);
}

TEST(SurfaceRoughness, ThinningMakesItIndependentOfTheDensity) {
  // the same noisy car sampled every 2 cm (a car at 5 m) and every 8 cm (at 20 m): without
  // thinning the dense one's tiny neighbourhoods see the noise, not the surface
  const Cloud dense = car_surface(0.02, 0.01, 4), sparse = car_surface(0.08, 0.01, 5);
  const double d = surface_roughness(dense.members, dense.points, 0.1, 10).median_variation;
  const double s = surface_roughness(sparse.members, sparse.points, 0.1, 10).median_variation;
  EXPECT_LT(d, 0.03);
  EXPECT_LT(s, 0.03);
  const double d_raw = surface_roughness(dense.members, dense.points, 0.005, 10).median_variation;
  EXPECT_GT(d_raw, 3.0 * d);  // the 1 cm noise over 2 cm spacing
}

TEST(SurfaceRoughness, TooFewReturnsAndBadArguments) {
  Cloud few;
  for (int i = 0; i < 8; ++i) few.add(0.3 * i, 1.0, 10.0);
  const SurfaceRoughness r = surface_roughness(few.members, few.points, 0.1, 10);
  EXPECT_EQ(r.num_points, 8);
  EXPECT_EQ(r.median_variation, 0.0);
  EXPECT_THROW(surface_roughness(few.members, few.points, 0.0, 10), std::invalid_argument);
  EXPECT_THROW(surface_roughness(few.members, few.points, 0.1, 2), std::invalid_argument);
}

TEST(Detector, HedgeIsNoCarByItsRoughnessWhileTheCarBesideItStays) {
  // a car-sized hedge beside a parked car: its leaves return from a layer up to 0.4 m deep
  // behind its outer faces, shallow enough for the faces' fit (edge distance < 0.25 m)
  const auto [car, hedge] = car_beside_foliage(5.0, 4.0, 1.6, 1.5);
  Points3 scan = cast_scene({car, hedge});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> depth(0.0, 0.4);
  const int leaves = push_returns_into(&scan, hedge, [&](const Vec3&) { return depth(rng); });
  ASSERT_GT(leaves, 300);

  DetectorOptions off;
  off.car_max_surface_variation = 0.0;
  const DetectorResult without = detect(scan, off);
  ASSERT_EQ(without.detections.size(), 2u);  // the fit alone takes the hedge for a car
  for (const Detection& d : without.detections) EXPECT_EQ(d.cls, ObjectClass::kCar);

  const DetectorResult with = detect(scan);
  ASSERT_EQ(with.detections.size(), 1u);
  EXPECT_NEAR(with.detections[0].centre.x(), car.x, 0.35);
  EXPECT_GT(with.detections[0].surface_variation, 0.0);  // judged, and smooth
  EXPECT_LT(with.detections[0].surface_variation, 0.03);
}
