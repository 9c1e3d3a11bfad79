// The road behind an occluder (DetectorOptions::hold_road_in_shadows): past a parked car the
// ground is hidden below the car's shadow line, and the first returns beyond belong to
// whatever stands there. They must not become the road, or a building's face above the shadow
// stands on that raised "road" as a car-sized obstacle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "detection/detector.hpp"
#include "detection/ground_removal.hpp"
#include "detection/scene_points.hpp"
#include "synthetic_scene.hpp"

using namespace twistslam;
using namespace twistslam::detection;
using namespace twistslam::test_scenes;

namespace {

// A parked car 14 m ahead and 5 m to the left (along z), and behind it in its shadow a
// building 4 m tall, 11-13 m to the left, whose face runs along z from 28 to 32 m ahead: a
// kiosk, or a car-length piece of facade between two gaps (doorways, side streets).
struct ShadowScene {
  SceneBox parked, building;
  SceneRoad road;
  ShadowScene() {
    parked.x = -5.0;
    parked.z = 14.0;
    parked.yaw = M_PI / 2;  // along z
    parked.height = 1.5;
    building.x = -12.0;
    building.z = 30.0;
    building.yaw = M_PI / 2;
    building.length = 4.0;  // along z
    building.width = 2.0;
    building.height = 4.0;
  }
  // m, the highest road (up) the grid puts under the building's face (its bins hold the
  // face's lowest visible returns)
  float road_up_at_face(const DetectorOptions& o) const {
    const Points3 scan = cast_scene({parked, building}, road);
    const SceneSelection scene = select_scene_points(scan, o);
    const GroundGrid grid = estimate_ground(scene.points, o);
    float highest = -std::numeric_limits<float>::infinity();
    for (double dz = -0.5 * building.length; dz <= 0.5 * building.length; dz += 0.25)
      highest = std::max(highest, grid.road_at(building.x + 0.5 * building.width - 0.05,
                                               building.z + dz));
    return highest;
  }
};

}  // namespace

TEST(RoadInShadows, TheRoadBehindAParkedCarKeepsItsHeight) {
  const ShadowScene scene;
  DetectorOptions held, climbing;
  climbing.hold_road_in_shadows = false;
  const float road_up = static_cast<float>(-scene.road.sensor_height);
  // held: the road where it is (0.1 m: the bins' k-th lowest return on a noiseless road)
  EXPECT_NEAR(scene.road_up_at_face(held), road_up, 0.1);
  // without it the road climbs onto the facade's lowest visible row, over a metre up
  EXPECT_GT(scene.road_up_at_face(climbing) - road_up, 1.0);
}

TEST(RoadInShadows, AFacadeAboveTheShadowIsNoCar) {
  const ShadowScene scene;
  const Points3 scan = cast_scene({scene.parked, scene.building}, scene.road);
  auto cars_near_facade = [&](const DetectorOptions& o) {
    int n = 0;
    for (const Detection& d : detect(scan, o).detections)
      n += d.cls == ObjectClass::kCar && std::abs(d.centre.x() - scene.building.x) < 2.5 &&
           std::abs(d.centre.z() - scene.building.z) < 5.0;
    return n;
  };
  const DetectorResult r = detect(scan);
  int parked_cars = 0;
  for (const Detection& d : r.detections)
    parked_cars += d.cls == ObjectClass::kCar && std::abs(d.centre.x() - scene.parked.x) < 1.0 &&
                   std::abs(d.centre.z() - scene.parked.z) < 1.5;
  EXPECT_EQ(parked_cars, 1);  // the occluder itself stays a car
  EXPECT_EQ(cars_near_facade(DetectorOptions{}), 0);
  DetectorOptions climbing;
  climbing.hold_road_in_shadows = false;
  EXPECT_EQ(cars_near_facade(climbing), 1);  // the face above the shadow, on the raised road
}
