#pragma once
// A LiDAR-like scan of a car for the registration tests: random points on the faces of a
// body box and a smaller cabin box on top (the cabin breaks the box's symmetries), the faces a
// sensor at the origin sees, Gaussian noise. Camera frame: x right, y down, z forward.
#include <random>
#include <vector>

#include "geometry/se3.hpp"
#include "geometry/types.hpp"

namespace twistslam::test {

struct BoxFace {
  Vec3 corner, u, v;  // the face is corner + a u + b v, a, b in [0, 1]
};

// The faces seen from the origin of an axis-aligned box centred at c with half sizes h: one
// per axis, the one facing the origin.
inline std::vector<BoxFace> visible_faces(const Vec3& c, const Vec3& h) {
  std::vector<BoxFace> faces;
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    Vec3 corner = c - h;
    if (c[axis] < 0) corner[axis] = c[axis] + h[axis];  // the far side faces the origin
    Vec3 u = Vec3::Zero(), v = Vec3::Zero();
    u[a] = 2 * h[a];
    v[b] = 2 * h[b];
    faces.push_back({corner, u, v});
  }
  return faces;
}

// n points (about, split by face area) of a car at `centre`, noise sigma_m per axis.
inline Points3 car_scan(const Vec3& centre, int n, double sigma_m, unsigned seed) {
  const Vec3 body_half(2.0, 0.45, 0.85);                 // 4 m long, 0.9 m body, 1.7 m wide
  const Vec3 cabin_centre = centre + Vec3(-0.3, -0.75, 0.0);
  const Vec3 cabin_half(1.1, 0.3, 0.7);
  std::vector<BoxFace> faces = visible_faces(centre, body_half);
  for (const BoxFace& f : visible_faces(cabin_centre, cabin_half)) faces.push_back(f);
  std::vector<double> area;
  double total = 0.0;
  for (const BoxFace& f : faces) total += f.u.norm() * f.v.norm(), area.push_back(total);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma_m);
  Points3 points(n, 3);
  for (int i = 0; i < n; ++i) {
    const double pick = unit(rng) * total;
    std::size_t k = 0;
    while (k + 1 < faces.size() && area[k] < pick) ++k;
    const Vec3 p = faces[k].corner + unit(rng) * faces[k].u + unit(rng) * faces[k].v;
    points.row(i) = (p + Vec3(noise(rng), noise(rng), noise(rng))).transpose();
  }
  return points;
}

// Applies T to every row.
inline Points3 transformed(const Points3& points, const Mat4& T) {
  Points3 out(points.rows(), 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    out.row(i) = (T.topLeftCorner<3, 3>() * points.row(i).transpose() + T.topRightCorner<3, 1>())
                     .transpose();
  return out;
}

// A new sampling of the car as the source scan of a registration whose true result is
// T_target_source: the car seen after moving by T_target_source^-1.
inline Points3 source_scan(const Vec3& centre, const Mat4& T_target_source, int n, double sigma_m,
                           unsigned seed) {
  return transformed(car_scan(centre, n, sigma_m, seed), geometry::se3_inverse(T_target_source));
}

}  // namespace twistslam::test
