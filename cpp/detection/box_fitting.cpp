#include "detection/box_fitting.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace twistslam::detection {

namespace {
struct Extremes {
  double lo0, hi0, lo1, hi1;
};

Extremes extremes(const std::vector<BevPoint>& pts, double c, double s) {
  Extremes e{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const BevPoint& p : pts) {
    const double a = p.x * c + p.z * s, b = -p.x * s + p.z * c;
    e.lo0 = std::min(e.lo0, a);
    e.hi0 = std::max(e.hi0, a);
    e.lo1 = std::min(e.lo1, b);
    e.hi1 = std::max(e.hi1, b);
  }
  return e;
}

// distance of every return to the nearest edge of the enclosing rectangle at (c, s): summed
// inverse (closeness, floored) and summed plain (for the mean)
void edge_distances(const std::vector<BevPoint>& pts, double c, double s, const Extremes& e,
                    double floor_m, double* closeness, double* total) {
  double inv = 0, sum = 0;
  for (const BevPoint& p : pts) {
    const double a = p.x * c + p.z * s, b = -p.x * s + p.z * c;
    const double d = std::min(std::min(a - e.lo0, e.hi0 - a), std::min(b - e.lo1, e.hi1 - b));
    inv += 1.0 / std::max(d, floor_m);
    sum += d;
  }
  *closeness = inv;
  *total = sum;
}
}  // namespace

BevPoint BevRectangle::axis_direction(int axis) const {
  const double c = std::cos(heading), s = std::sin(heading);
  return axis == 0 ? BevPoint{c, s} : BevPoint{-s, c};
}

BevPoint BevRectangle::centre() const {
  const double a = 0.5 * (lo[0] + hi[0]), b = 0.5 * (lo[1] + hi[1]);
  const BevPoint e0 = axis_direction(0), e1 = axis_direction(1);
  return {a * e0.x + b * e1.x, a * e0.z + b * e1.z};
}

void BevRectangle::extend_away_from_sensor(int axis, double size) {
  // the sensor projects to 0: a rectangle beyond it (centre > 0) grows its far edge hi
  extend_edge(axis, size, lo[axis] + hi[axis] >= 0.0);
}

void BevRectangle::extend_edge(int axis, double size, bool grow_hi) {
  if (extent(axis) >= size) return;
  if (grow_hi) {
    hi[axis] = lo[axis] + size;
  } else {
    lo[axis] = hi[axis] - size;
  }
}

BevRectangle fit_rectangle(const std::vector<BevPoint>& points, const DetectorOptions& o) {
  std::vector<BevPoint> sample;
  const std::vector<BevPoint>* pts = &points;
  if (static_cast<int>(points.size()) > o.max_fit_points) {
    const double stride = static_cast<double>(points.size()) / o.max_fit_points;
    sample.reserve(o.max_fit_points);
    for (int i = 0; i < o.max_fit_points; ++i) sample.push_back(points[static_cast<std::size_t>(i * stride)]);
    pts = &sample;
  }
  const double step = o.heading_step_deg * M_PI / 180.0;
  const int steps = std::max(1, static_cast<int>(std::ceil(0.5 * M_PI / step - 1e-9)));
  double best_closeness = -1, best_heading = 0;
  for (int k = 0; k < steps; ++k) {
    const double theta = k * step, c = std::cos(theta), s = std::sin(theta);
    double closeness = 0, total = 0;
    edge_distances(*pts, c, s, extremes(*pts, c, s), o.closeness_floor_m, &closeness, &total);
    if (closeness > best_closeness) {
      best_closeness = closeness;
      best_heading = theta;
    }
  }
  BevRectangle r;
  r.heading = best_heading;
  const double c = std::cos(best_heading), s = std::sin(best_heading);
  const Extremes e = extremes(points, c, s);  // all returns: the subsample may miss a corner
  r.lo[0] = e.lo0;
  r.hi[0] = e.hi0;
  r.lo[1] = e.lo1;
  r.hi[1] = e.hi1;
  double closeness = 0, total = 0;
  edge_distances(*pts, c, s, e, o.closeness_floor_m, &closeness, &total);
  r.mean_edge_distance = pts->empty() ? 0.0 : total / static_cast<double>(pts->size());
  return r;
}

}  // namespace twistslam::detection
