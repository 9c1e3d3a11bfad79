#pragma once
// Small helpers shared by the detector's tests: finding a car box and printing the boxes.
#include <cmath>
#include <string>

#include "detection/detector.hpp"

namespace twistslam::test_scenes {

// The car detection nearest (BEV) to (x, z), or nullptr when there is none.
inline const detection::Detection* nearest_car(const detection::DetectorResult& r, double x,
                                               double z) {
  const detection::Detection* best = nullptr;
  for (const detection::Detection& d : r.detections)
    if (d.cls == detection::ObjectClass::kCar &&
        (!best || std::hypot(d.centre.x() - x, d.centre.z() - z) <
                      std::hypot(best->centre.x() - x, best->centre.z() - z)))
      best = &d;
  return best;
}

// Person and cyclist detections within 0.8 m (BEV) of (x, z).
inline int people_near(const detection::DetectorResult& r, double x, double z) {
  int n = 0;
  for (const detection::Detection& d : r.detections)
    n += d.cls != detection::ObjectClass::kCar && std::hypot(d.centre.x() - x, d.centre.z() - z) < 0.8;
  return n;
}

// The detections as text, for failure messages.
inline std::string describe(const detection::DetectorResult& r) {
  std::string out;
  for (const detection::Detection& d : r.detections)
    out += std::string(detection::to_string(d.cls)) + " x " + std::to_string(d.centre.x()) +
           " z " + std::to_string(d.centre.z()) + " l " + std::to_string(d.length) + " w " +
           std::to_string(d.width) + " yaw " + std::to_string(d.yaw * 180.0 / M_PI) + " n " +
           std::to_string(d.num_points) + "; ";
  return out;
}

}  // namespace twistslam::test_scenes
