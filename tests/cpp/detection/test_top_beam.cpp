// Posts cut by the top beam (top_beam.hpp, DetectorOptions::person_top_beam_margin_m): the
// LiDAR's highest beam (+2 deg in the synthetic sensor, as the HDL-64's) is fitted to the scan's
// upper envelope; a thin pole near the sensor ends on it at person height, a person's head
// lies well below it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "detection/detector.hpp"
#include "detection/scene_points.hpp"
#include "detection/top_beam.hpp"
#include "detection_test_helpers.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::detection;
using namespace twistslam::test_scenes;

namespace {

const double kTopBeamSlope = std::tan(2.0 * M_PI / 180.0);  // the synthetic sensor's top beam

// Facades 12 m tall along both sides of the road, x = +-9 m, from 2 to 70 m ahead, and one
// across it 35 m ahead: the top beam hits them at 12-37 m.
std::vector<SceneBox> street_facades() {
  std::vector<SceneBox> walls;
  for (const double x : {-9.0, 9.0}) {
    SceneBox wall;
    wall.x = x;
    wall.z = 36.0;
    wall.length = 68.0;
    wall.width = 0.5;
    wall.height = 12.0;
    wall.yaw = M_PI / 2;  // length along z
    walls.push_back(wall);
  }
  SceneBox across;
  across.z = 35.0;
  across.length = 18.0;  // yaw 0: along x
  across.width = 0.5;
  across.height = 12.0;
  walls.push_back(across);
  return walls;
}

std::vector<ScenePoint> scene_points(const Points3& scan) {
  std::vector<ScenePoint> pts;
  for (Eigen::Index i = 0; i < scan.rows(); ++i)
    pts.push_back({static_cast<float>(scan(i, 0)), static_cast<float>(scan(i, 2)),
                   static_cast<float>(-scan(i, 1)), static_cast<int>(i)});
  return pts;
}

}  // namespace

TEST(TopBeam, TheFacadesGiveTheHighestBeamsCone) {
  const TopBeam beam = fit_top_beam(scene_points(cast_scene(street_facades())));
  ASSERT_TRUE(beam.valid) << "bins " << beam.num_bins << " rms " << beam.rms_m << " a " << beam.a << " b " << beam.b << " c " << beam.c << " d " << beam.d;
  EXPECT_NEAR(beam.b, kTopBeamSlope, 0.002);
  EXPECT_LT(beam.rms_m, 0.01);
  for (const auto& [x, z] : std::vector<std::pair<double, double>>{{0, 8}, {0, 20}, {5, 30}, {-4, 12}})
    EXPECT_NEAR(beam.up_at(x, z), std::hypot(x, z) * kTopBeamSlope, 0.03) << "at x " << x << " z " << z;
}

TEST(TopBeam, AnOpenRoadHasNoBeamToJudgeBy) {
  // parked cars only: the envelope is their roofs, flat, not a cone
  std::vector<SceneBox> cars;
  for (int i = 0; i < 6; ++i) {
    SceneBox car;
    car.x = i % 2 ? 4.0 : -4.0;
    car.z = 8.0 + 5.0 * i;
    car.yaw = M_PI / 2;
    cars.push_back(car);
  }
  const TopBeam roofs = fit_top_beam(scene_points(cast_scene(cars)));
  EXPECT_FALSE(roofs.valid) << "bins " << roofs.num_bins << " rms " << roofs.rms_m << " a " << roofs.a
                            << " b " << roofs.b << " c " << roofs.c << " d " << roofs.d;
  EXPECT_FALSE(fit_top_beam({}).valid);
}

TEST(TopBeam, APostCutByTheBeamIsNoPersonWhileAPersonStays) {
  const SceneBox body = person_body(2.5, 12.0);
  const SceneBox pole = post(-3.0, 6.5, 0.12, 5.0);  // cut at 1.73 + 7.2 tan(2 deg) = 1.98 m
  std::vector<SceneBox> scene = street_facades();
  scene.push_back(body);
  scene.push_back(head_on(body));
  scene.push_back(pole);
  const Points3 scan = cast_scene(scene);
  DetectorOptions options;
  options.person_max_head_ratio = 0.0;  // the outline rule off: this rule alone
  const DetectorResult r = detect(scan, options);
  EXPECT_EQ(people_near(r, body.x, body.z), 1) << describe(r);
  EXPECT_EQ(people_near(r, pole.x, pole.z), 0) << describe(r);
  // the rule that removed it: without it the pole is a person
  options.person_top_beam_margin_m = 0.0;
  const DetectorResult all = detect(scan, options);
  EXPECT_EQ(people_near(all, pole.x, pole.z), 1) << describe(all);

  // in an open field (no facades) there is no beam to judge by: no person is dropped
  const Points3 open = cast_scene({body, head_on(body), pole});
  options.person_top_beam_margin_m = 0.08;
  const DetectorResult field = detect(open, options);
  EXPECT_EQ(people_near(field, body.x, body.z), 1) << describe(field);
  EXPECT_EQ(people_near(field, pole.x, pole.z), 1) << describe(field);
}
