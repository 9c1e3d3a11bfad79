#pragma once
// A ray-cast LiDAR scene for the detector tests: a spinning multi-beam sensor at the camera
// origin of frame c (x right, y down, z forward), a road plane below it (optionally sloped)
// and upright boxes standing on it. Returns are the nearest hit of every ray, without noise,
// so every tolerance of the tests is the detector's own error.
#include <cmath>
#include <limits>
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::test_scenes {

struct SceneBox {
  double x = 0, z = 0;          // m, footprint centre
  double length = 4.0, width = 1.7, height = 1.5;  // m
  double yaw = 0;               // rad, KITTI rotation_y
  double lift = 0;              // m, gap between the road and the box's bottom
};

struct SceneRoad {
  double sensor_height = 1.73;  // m, the KITTI HDL-64 above the road
  double slope = 0;             // rise (m) of the road per m of z ahead
};

// m of y (down) of the road at depth z
inline double road_y(const SceneRoad& road, double z) { return road.sensor_height - road.slope * z; }

// Distance along unit ray d from the origin to box b (standing on `road`), +inf if missed.
inline double hit_box(const Vec3& d, const SceneBox& b, const SceneRoad& road) {
  const double c = std::cos(b.yaw), s = std::sin(b.yaw);
  const double y_bottom = road_y(road, b.z) - b.lift;  // y grows downwards
  const Vec3 centre(b.x, y_bottom - 0.5 * b.height, b.z);
  // box axes in frame c: length along (c, 0, -s), width along (s, 0, c), height along y
  const Vec3 axes[3] = {Vec3(c, 0, -s), Vec3(0, 1, 0), Vec3(s, 0, c)};
  const double half[3] = {0.5 * b.length, 0.5 * b.height, 0.5 * b.width};
  double t_in = 0, t_out = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double o = -centre.dot(axes[k]), v = d.dot(axes[k]);
    if (std::abs(v) < 1e-12) {
      if (std::abs(o) > half[k]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double t0 = (-half[k] - o) / v, t1 = (half[k] - o) / v;
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  return t_in <= t_out && t_in > 0 ? t_in : std::numeric_limits<double>::infinity();
}

// A person's body up to the shoulders (1.5 m; add head_on for the head): `across` m wide
// across the line of sight (yaw 0: length along x), `depth` m along it.
inline SceneBox person_body(double x, double z, double across = 0.5, double depth = 0.3) {
  SceneBox body;
  body.x = x;
  body.z = z;
  body.length = across;
  body.width = depth;
  body.height = 1.5;
  return body;
}

// A head (0.2 m wide, 0.25 m tall) standing on `body`'s top: people are narrower at the top
// than at the shoulders, which tells them from posts (person_outline.hpp).
inline SceneBox head_on(const SceneBox& body) {
  SceneBox head = body;
  head.length = head.width = 0.2;
  head.height = 0.25;
  head.lift = body.lift + body.height;
  return head;
}

// A post (a pole, a tree trunk) of square cross-section `thickness` (m), `height` m tall.
inline SceneBox post(double x, double z, double thickness, double height) {
  SceneBox b;
  b.x = x;
  b.z = z;
  b.length = b.width = thickness;
  b.height = height;
  return b;
}

// Scan of the scene: 64 beams from -24.8 to +2 deg elevation (the HDL-64's span), one
// return every azimuth_step_deg over +-azimuth_span_deg around the z axis, up to 80 m.
inline Points3 cast_scene(const std::vector<SceneBox>& boxes, const SceneRoad& road = {},
                          double azimuth_step_deg = 0.2, double azimuth_span_deg = 50.0) {
  constexpr int kBeams = 64;
  constexpr double kLowestDeg = -24.8, kHighestDeg = 2.0, kMaxRange = 80.0;
  std::vector<Vec3> pts;
  for (int b = 0; b < kBeams; ++b) {
    const double el = (kLowestDeg + (kHighestDeg - kLowestDeg) * b / (kBeams - 1)) * M_PI / 180.0;
    for (double az = -azimuth_span_deg; az <= azimuth_span_deg; az += azimuth_step_deg) {
      const double a = az * M_PI / 180.0;
      const Vec3 d(std::cos(el) * std::sin(a), -std::sin(el), std::cos(el) * std::cos(a));
      double t = std::numeric_limits<double>::infinity();
      // road: y = h - slope z  <=>  t (d.y + slope d.z) = h
      const double denom = d.y() + road.slope * d.z();
      if (denom > 1e-9) t = road.sensor_height / denom;
      for (const SceneBox& box : boxes) t = std::min(t, hit_box(d, box, road));
      if (t < kMaxRange) pts.push_back(t * d);
    }
  }
  Points3 out(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  return out;
}

// A parked car at x = -3 m and a car-sized stand of foliage at foliage_x, both 14 m ahead and
// along z (yaw pi/2): the scene of the vegetation tests.
struct CarBesideFoliage {
  SceneBox car, foliage;
};
inline CarBesideFoliage car_beside_foliage(double foliage_x, double length, double width,
                                           double height) {
  CarBesideFoliage s;
  s.car.x = -3.0;
  s.car.z = 14.0;
  s.car.yaw = 0.5 * M_PI;
  s.foliage.x = foliage_x;
  s.foliage.z = 14.0;
  s.foliage.length = length;
  s.foliage.width = width;
  s.foliage.height = height;
  s.foliage.yaw = 0.5 * M_PI;
  return s;
}

// Whether p lies in the footprint of an upright box along z (yaw pi/2), above the flat road.
inline bool in_box_along_z(const Vec3& p, const SceneBox& b, const SceneRoad& road = {}) {
  return std::abs(p.x() - b.x) <= 0.5 * b.width + 1e-6 &&
         std::abs(p.z() - b.z) <= 0.5 * b.length + 1e-6 && p.y() < road.sensor_height - 1e-6;
}

// Moves every return of `scan` on the box (along z) further along its ray by step(p) m:
// foliage lets the beams in, so its returns lie behind its faces. Returns how many moved.
template <typename Step>
int push_returns_into(Points3* scan, const SceneBox& box, Step step) {
  int moved = 0;
  for (Eigen::Index i = 0; i < scan->rows(); ++i) {
    const Vec3 p = scan->row(i).transpose();
    if (!in_box_along_z(p, box)) continue;
    ++moved;
    scan->row(i) = (p * (1.0 + step(p) / p.norm())).transpose();
  }
  return moved;
}

// |a - b| modulo pi, in [0, pi/2]: a LiDAR box has no front.
inline double yaw_error_mod_pi(double a, double b) {
  double e = std::fmod(std::abs(a - b), M_PI);
  return std::min(e, M_PI - e);
}

}  // namespace twistslam::test_scenes
