// A far car seen end-on loses its bumper to the clustering: the ring above the bumper passes
// over the hood and lands on the windshield a hood's length behind, farther than
// cluster_gap_m. The bumper's low cluster is joined back to the body behind it
// (fragment_merge.hpp), so the box is laid with the prior's length from the bumper, not from
// the windshield; a low object beside a car, or a near one in front of it, is not joined.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "detection/detector.hpp"
#include "detection_test_helpers.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::detection;
using namespace twistslam::test_scenes;

namespace {

// A car heading towards the sensor along -z, its front at front_z: a lower body (bumper to
// hood, 0.75 m high) and a cabin set back by hood_m (its windshield base) on top of it.
std::vector<SceneBox> oncoming_car(double x, double front_z, double hood_m = 1.2) {
  SceneBox body;
  body.x = x;
  body.length = 4.2;
  body.width = 1.7;
  body.height = 0.75;
  body.z = front_z + 0.5 * body.length;
  body.yaw = 0.5 * M_PI;
  SceneBox cabin = body;
  cabin.length = 2.4;
  cabin.width = 1.6;
  cabin.height = 0.7;
  cabin.lift = body.height;
  cabin.z = front_z + hood_m + 0.5 * cabin.length;
  return {body, cabin};
}

DetectorOptions without_merge() {
  DetectorOptions o;
  o.fragment_merge_gap_m = 0.0;
  return o;
}

}  // namespace

TEST(FragmentMerge, AFarCarsBumperJoinsItsBodyAndTheBoxStartsAtTheBumper) {
  for (const double front_z : {42.0, 47.0}) {
    SCOPED_TRACE("front at z = " + std::to_string(front_z));
    const std::vector<SceneBox> car = oncoming_car(1.0, front_z);
    const double centre_z = car[0].z;
    const Points3 scan = cast_scene(car);
    // without the merge the bumper is cut off: the box starts at the windshield
    const DetectorResult cut = detect(scan, without_merge());
    const Detection* d_cut = nearest_car(cut, 1.0, centre_z);
    ASSERT_NE(d_cut, nullptr);
    EXPECT_GT(std::abs(d_cut->centre.z() - 0.5 * d_cut->length - front_z), 0.8)
        << "the scene no longer splits the bumper off; the test shows nothing";
    const DetectorResult merged = detect(scan);
    const Detection* d = nearest_car(merged, 1.0, centre_z);
    ASSERT_NE(d, nullptr);
    SCOPED_TRACE("merged: " + describe(merged) + " / cut: " + describe(cut));
    EXPECT_NEAR(d->centre.z() - 0.5 * d->length, front_z, 0.15);  // the near end: the bumper
    EXPECT_GT(d->num_points, d_cut->num_points);
  }
}

TEST(FragmentMerge, ALowObjectBesideACarOrANearOneIsNotJoined) {
  // a low wall segment (a kerb-side planter) 1 m beside a far car's body, not in front of it
  std::vector<SceneBox> scene = oncoming_car(1.0, 44.0);
  SceneBox planter;
  planter.x = 1.0 + 0.85 + 1.0 + 0.5;
  planter.z = 46.0;
  planter.length = 1.0;
  planter.width = 1.0;
  planter.height = 0.5;
  scene.push_back(planter);
  const Points3 scan = cast_scene(scene);
  const DetectorResult r = detect(scan);
  SCOPED_TRACE("detections: " + describe(r));
  const Detection* car = nearest_car(r, 1.0, 46.1);
  ASSERT_NE(car, nullptr);
  EXPECT_LT(car->width, 1.8);  // the planter did not widen the car
  EXPECT_NEAR(car->centre.x(), 1.0, 0.1);
  EXPECT_NEAR(car->centre.z() - 0.5 * car->length, 44.0, 0.15);  // its bumper did join

  // fragments nearer than fragment_min_range_m stay out: with the range raised past the car
  // the detections are those without the merge (here: the bumper-less body is no car)
  DetectorOptions far_only;
  far_only.fragment_min_range_m = 60.0;
  const DetectorResult r_far_only = detect(scan, far_only), r_off = detect(scan, without_merge());
  ASSERT_EQ(r_far_only.detections.size(), r_off.detections.size()) << describe(r_far_only);
  ASSERT_LT(r_off.detections.size(), r.detections.size());  // the merge made the car here
  for (std::size_t i = 0; i < r_off.detections.size(); ++i)
    EXPECT_NEAR(r_far_only.detections[i].centre.z(), r_off.detections[i].centre.z(), 1e-9);

  // a near car (12 m) whose bumper is joined by the clustering anyway keeps its box whether
  // or not the merge runs
  const Points3 near_scan = cast_scene(oncoming_car(1.0, 12.0));
  const DetectorResult near_with = detect(near_scan), near_without = detect(near_scan, without_merge());
  const Detection* a = nearest_car(near_with, 1.0, 14.1);
  const Detection* b = nearest_car(near_without, 1.0, 14.1);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_NEAR(a->centre.z(), b->centre.z(), 1e-9);
  EXPECT_EQ(a->num_points, b->num_points);
}

TEST(FragmentMerge, InvalidOptionsAreRefused) {
  DetectorOptions o;
  o.fragment_merge_gap_m = -1.0;
  EXPECT_THROW(detect(Points3(0, 3), o), std::invalid_argument);
}
