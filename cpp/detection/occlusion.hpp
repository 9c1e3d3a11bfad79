#pragma once
// What hides the ends of a cluster: a small range image (azimuth x elevation bins) of the
// nearest obstacle return, so that a car whose end lies behind a nearer object (a parked
// row) or past the region of interest (a car beside the ego car) grows its box there, not
// away from the sensor.
#include <vector>

#include "detection/scene_points.hpp"

namespace twistslam::detection {

// Azimuth (rad, atan2(x, z): 0 straight ahead, positive to the right) of a BEV point.
double azimuth_of(double x, double z);

// Nearest obstacle range per (azimuth, elevation) bin over the selected field.
class OcclusionMap {
 public:
  // points: the selection; obstacle[i] != 0 for the obstacle returns; half_angle_deg: half
  // the field the points were selected in (180: the whole turn).
  OcclusionMap(const std::vector<ScenePoint>& points, const std::vector<char>& obstacle,
               double half_angle_deg);

  // Whether the view just past one azimuth edge of a cluster is hidden: the field ends there,
  // or for at least half of the cluster's returns at that edge, a return of the same
  // elevation a little further round is clearly nearer. side: -1 for the cluster's smallest
  // azimuth, +1 for its largest; members: the cluster's rows of points.
  bool hidden_beyond(const std::vector<ScenePoint>& points, const std::vector<int>& members,
                     int side) const;

 private:
  int azimuth_bin(double az_rad) const;
  int elevation_bin(double up_m, double range_m) const;
  double half_angle_rad_;
  int azimuth_bins_ = 0;
  std::vector<float> nearest_;  // m, azimuth-major; +inf where a bin has no obstacle return
};

}  // namespace twistslam::detection
