// A far car sampled by a few beam rings, as the HDL-64E samples a car at 35-55 m: the heading
// of its box comes from the few returns of the body's faces, not from the rings crossing the
// cabin (each a line across the line of sight) nor from stray returns lined up with the far
// edges of the rectangle.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "detection/detector.hpp"
#include "detection_test_helpers.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::detection;
using namespace twistslam::test_scenes;

namespace {
constexpr double kDeg = M_PI / 180.0;
// deg, the heading search's step is 1 deg; a face of a few returns may tilt the fit by a step
// or two more
constexpr double kFarYawToleranceDeg = 3.0;

// A car as boxes standing at (x, z) with KITTI yaw `yaw`: a body up to 1 m whose ends are
// narrower (the rounded corners of a real body: a 3.7 m mid part 1.76 m wide, 4.2 m at
// 1.45 m) and a cabin from 1.0 to 1.5 m (2.2 x 1.35 m, set back 0.3 m), whose windows and
// roof the upper rings cross.
std::vector<SceneBox> car_shape(double x, double z, double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  SceneBox mid, ends, cabin;
  mid.x = ends.x = x;
  mid.z = ends.z = z;
  mid.yaw = ends.yaw = cabin.yaw = yaw;
  mid.length = 3.7;
  mid.width = 1.76;
  ends.length = 4.2;
  ends.width = 1.45;
  mid.lift = ends.lift = 0.3;
  mid.height = ends.height = 0.7;
  cabin.length = 2.2;
  cabin.width = 1.35;
  cabin.lift = 1.0;
  cabin.height = 0.5;
  cabin.x = x - 0.3 * c;  // set back along the length axis (cos yaw, -sin yaw) in (x, z)
  cabin.z = z + 0.3 * s;
  return {mid, ends, cabin};
}

// m, the HDL-64E's range noise (1 sigma)
constexpr double kRangeNoiseM = 0.02;

// `points` with Gaussian noise of kRangeNoiseM along each ray (a fixed seed: repeatable)
Points3 with_range_noise(Points3 points, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kRangeNoiseM);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const double r = points.row(i).norm();
    points.row(i) *= (r + noise(rng)) / r;
  }
  return points;
}

}  // namespace

// A parked row ahead, right of the lane: the nearer car hides most of the far one's rear at
// 40 m, which shows its corner and a few returns of its side, seen at a grazing angle (10 of
// its 10-14 returns below 1 m, rings crossing its cabin above). The previous fit took the
// heading from all returns when fewer than min_cluster_points lay below 1 m, and lined up
// stray returns with the far edges: 8-15 deg off.
TEST(SparseFarCar, PartlyHiddenCarOfAParkedRowGetsItsHeading) {
  const double x = 4.0, z = 40.0, yaw = 0.5 * M_PI, gap_m = 1.5;
  std::vector<SceneBox> boxes = car_shape(x, z, yaw);
  const std::vector<SceneBox> nearer = car_shape(x, z - 4.2 - gap_m, yaw);
  boxes.insert(boxes.end(), nearer.begin(), nearer.end());
  for (const unsigned seed : {1u, 2u}) {
    const DetectorResult r = detect(with_range_noise(cast_scene(boxes), seed));
    const Detection* d = nearest_car(r, x, z);
    ASSERT_NE(d, nullptr);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + std::to_string(d->num_points) +
                 " returns, yaw " + std::to_string(d->yaw / kDeg));
    ASSERT_LT(std::hypot(d->centre.x() - x, d->centre.z() - z), 2.0);  // the far car's box
    EXPECT_LT(yaw_error_mod_pi(d->yaw, yaw), kFarYawToleranceDeg * kDeg);
  }
}
