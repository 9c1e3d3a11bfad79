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

// Distance of a return at (a, b) (its projections on the two axes) to the nearest edge that
// faces the sensor. The sensor projects to 0 on both axes: an axis's lo edge faces it if
// lo > 0, its hi edge if hi < 0, neither if the sensor lies between them (then that axis's
// edges are seen edge-on or not at all). Returns can only lie on the faces the sensor sees:
// the far edges are set by the extreme returns themselves (the corner of an L, a lone return
// through a window) and scoring them rewards any heading that lines two stray returns up.
double facing_edge_distance(double a, double b, const Extremes& e) {
  constexpr double kUnseen = std::numeric_limits<double>::infinity();
  const double d0 = e.lo0 > 0 ? a - e.lo0 : e.hi0 < 0 ? e.hi0 - a : kUnseen;
  const double d1 = e.lo1 > 0 ? b - e.lo1 : e.hi1 < 0 ? e.hi1 - b : kUnseen;
  return std::min(d0, d1);
}

// Closeness of the returns to the sensor-facing edges of their enclosing rectangle at (c, s):
// sum of 1 / max(distance, floor_m).
double closeness(const std::vector<BevPoint>& pts, double c, double s, double floor_m) {
  const Extremes e = extremes(pts, c, s);
  double sum = 0;
  for (const BevPoint& p : pts)
    sum += 1.0 / std::max(facing_edge_distance(p.x * c + p.z * s, -p.x * s + p.z * c, e), floor_m);
  return sum;
}

// Mean distance of the returns to the nearest of all four edges (the fit term of the score).
double mean_edge_distance(const std::vector<BevPoint>& pts, double c, double s, const Extremes& e) {
  double sum = 0;
  for (const BevPoint& p : pts) {
    const double a = p.x * c + p.z * s, b = -p.x * s + p.z * c;
    sum += std::min(std::min(a - e.lo0, e.hi0 - a), std::min(b - e.lo1, e.hi1 - b));
  }
  return pts.empty() ? 0.0 : sum / static_cast<double>(pts.size());
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

double fit_heading(const std::vector<BevPoint>& points, const DetectorOptions& o) {
  std::vector<BevPoint> sample;
  const std::vector<BevPoint>* pts = &points;
  if (static_cast<int>(points.size()) > o.max_fit_points) {
    const double stride = static_cast<double>(points.size()) / o.max_fit_points;
    sample.reserve(o.max_fit_points);
    for (int i = 0; i < o.max_fit_points; ++i) sample.push_back(points[static_cast<std::size_t>(i * stride)]);
    pts = &sample;
  }
  // the floor follows the spacing of the returns, which grows with range (the azimuth step):
  // a far face's few returns are no more collinear than that spacing times its curvature
  double mean_x = 0, mean_z = 0;
  for (const BevPoint& p : *pts) {
    mean_x += p.x;
    mean_z += p.z;
  }
  const double range = std::hypot(mean_x, mean_z) / static_cast<double>(std::max<std::size_t>(1, pts->size()));
  const double floor_m = std::max(o.closeness_floor_m, o.closeness_floor_per_range * range);
  const double step = o.heading_step_deg * M_PI / 180.0;
  const int steps = std::max(1, static_cast<int>(std::ceil(0.5 * M_PI / step - 1e-9)));
  double best_closeness = -1, best_heading = 0;
  for (int k = 0; k < steps; ++k) {
    const double theta = k * step;
    const double score = closeness(*pts, std::cos(theta), std::sin(theta), floor_m);
    if (score > best_closeness) {
      best_closeness = score;
      best_heading = theta;
    }
  }
  return best_heading;
}

BevRectangle enclosing_rectangle(const std::vector<BevPoint>& points, double heading) {
  BevRectangle r;
  r.heading = heading;
  const double c = std::cos(heading), s = std::sin(heading);
  const Extremes e = extremes(points, c, s);
  r.lo[0] = e.lo0;
  r.hi[0] = e.hi0;
  r.lo[1] = e.lo1;
  r.hi[1] = e.hi1;
  r.mean_edge_distance = mean_edge_distance(points, c, s, e);
  return r;
}

BevRectangle fit_rectangle(const std::vector<BevPoint>& points, const DetectorOptions& o) {
  return enclosing_rectangle(points, fit_heading(points, o));
}

}  // namespace twistslam::detection
