#pragma once
// From a fitted cluster to a detection: class from size and shape (Car, Pedestrian, Cyclist,
// or rejected), the car-size prior for partial views, and a score in (0, 1].
#include <cstdint>
#include <optional>

#include "detection/box_fitting.hpp"
#include "geometry/types.hpp"

namespace twistslam::detection {

enum class ObjectClass : std::uint8_t { kCar = 0, kPedestrian = 1, kCyclist = 2 };

// KITTI type name: "Car", "Pedestrian", "Cyclist".
const char* to_string(ObjectClass cls);

// A 3D box in the rectified camera frame c, as python/twistslam/perception/detection.py.
struct Detection {
  Vec3 centre = Vec3::Zero();  // m, geometric centre (not KITTI's bottom centre)
  double length = 0, width = 0, height = 0;  // m, along the heading, across it, vertical
  // rad, KITTI rotation_y: in [-pi, pi) pointing to the car's front if heading_known, else in
  // [-pi/2, pi/2) (the L-shape fit knows it mod pi)
  double yaw = 0;
  double score = 0;    // (0, 1]: point count x fit quality x share of the box seen
  ObjectClass cls = ObjectClass::kCar;
  int num_points = 0;  // obstacle returns of the cluster
  // cars: the length was measured (an L-shape of two faces), not the car_length_m prior;
  // a box without it has its centre only as good as the prior (+- 0.2-0.3 m along the yaw)
  bool length_seen = false;
  // cars without length_seen: the end of the box (+1 its +x end, along the yaw's heading; -1
  // its -x end) that the prior extended past the seen face; 0 for a measured length. With a
  // car's true length known (other frames), the centre moves by (true - length) / 2 that way.
  int open_end = 0;
  // cars with length_seen: the front was told from the height profile (front_profile.hpp)
  bool heading_known = false;
  // m, mean distance of the footprint's returns to the nearest edge of their fitted
  // rectangle: a car's faces give a few cm, volumetric clutter (a bush, a hedge) tenths
  double edge_distance_m = 0;
  // cars: the median surface variation of the cluster's returns (surface_roughness.hpp; 0
  // when car_max_surface_variation is off or the cluster too sparse to judge)
  double surface_variation = 0;
};

struct ClusterShape {
  BevRectangle footprint;  // L-shape fit of the returns
  double road_up = 0;      // m, road height (up = -y) under the cluster (its lowest cell)
  double top_m = 0;        // m, highest return above the road
  double bottom_m = 0;     // m, lowest return above the road
  // m, extent along the footprint's longer axis of the returns above footprint_max_height_m
  // (0 without such returns): a car's rear window spans most of its width, a cyclist's torso
  // a third of the bicycle's length
  double upper_extent_m = 0;
  int num_points = 0;
  // something nearer than the cluster (or the end of the field) hides the view just past its
  // smallest / largest azimuth: the object may go on there (occlusion.hpp)
  bool hidden_low_azimuth = false, hidden_high_azimuth = false;
};

// The detection the cluster is, or nullopt (too tall, too big, floating, no class fits).
std::optional<Detection> classify(const ClusterShape& shape, const DetectorOptions& options);

}  // namespace twistslam::detection
