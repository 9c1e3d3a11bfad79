#pragma once
// L-shape fitting of a cluster's bird's-eye-view footprint: the heading of the rectangle whose
// sensor-facing edges the returns hug most closely (closeness criterion: sum over the returns
// of the inverse distance to the nearest edge facing the sensor, floored by a distance that
// grows with range, searched over [0, 90) deg), then the enclosing rectangle at that heading. A LiDAR sees one face or two faces (an L) of a car; both give a sharp maximum
// at the car's heading, where an enclosing-area criterion is flat for a single face.
#include <vector>

#include "detection/detector_options.hpp"

namespace twistslam::detection {

struct BevPoint {
  double x = 0, z = 0;  // m, camera x (right) and z (forward)
};

// A rectangle in a local frame: axis 0 has direction (cos heading, sin heading) in (x, z),
// axis 1 is axis 0 turned +90 deg. lo / hi are the edge coordinates along each axis (m,
// projections of (x, z) on the axis, so the sensor at the origin projects to 0).
struct BevRectangle {
  double heading = 0;                // rad, direction of axis 0 from the x axis towards z
  double lo[2] = {0, 0}, hi[2] = {0, 0};
  double mean_edge_distance = 0;     // m, mean distance of the returns to their nearest edge

  double extent(int axis) const { return hi[axis] - lo[axis]; }
  // Direction (x, z) of `axis`.
  BevPoint axis_direction(int axis) const;
  // Centre (x, z) of the rectangle.
  BevPoint centre() const;
  // Grows `axis` to `size` m (if shorter) by moving the edge farther from the sensor, the
  // side a LiDAR cannot see.
  void extend_away_from_sensor(int axis, double size);
  // Grows `axis` to `size` m (if shorter) by moving its hi edge (grow_hi) or its lo edge.
  void extend_edge(int axis, double size, bool grow_hi);
};

// Heading in [0, pi/2) of the L-shape fit of `points` (at least 1; a regular subsample of
// max_fit_points is used for larger sets); options must be valid.
double fit_heading(const std::vector<BevPoint>& points, const DetectorOptions& options);

// The rectangle at `heading` enclosing `points` (at least 1), with their mean edge distance.
BevRectangle enclosing_rectangle(const std::vector<BevPoint>& points, double heading);

// Best rectangle of `points`: enclosing_rectangle(points, fit_heading(points, options)).
BevRectangle fit_rectangle(const std::vector<BevPoint>& points, const DetectorOptions& options);

}  // namespace twistslam::detection
