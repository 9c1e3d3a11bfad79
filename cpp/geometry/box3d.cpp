#include "geometry/box3d.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/se3.hpp"

namespace twistslam::geometry {
namespace {
Mat3 rot_y(double a) {
  Mat3 R;
  R << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return R;
}
// Corner signs (x along length, z along width) in counter-clockwise order seen from above.
constexpr double kSx[4] = {1, 1, -1, -1};
constexpr double kSz[4] = {1, -1, -1, 1};
}  // namespace

Box3D Box3D::from_row(const double* r) {
  Box3D b;
  b.center = Vec3(r[0], r[1], r[2]);
  b.length = r[3];
  b.width = r[4];
  b.height = r[5];
  b.yaw = r[6];
  return b;
}

Mat4 Box3D::pose() const { return make_pose(rot_y(yaw), center); }

std::array<Vec3, 8> Box3D::corners() const {
  const Mat3 R = rot_y(yaw);
  std::array<Vec3, 8> out;
  for (int face = 0; face < 2; ++face) {
    const double y = face == 0 ? 0.5 * height : -0.5 * height;  // y points down: bottom first
    for (int k = 0; k < 4; ++k) {
      out[face * 4 + k] = center + R * Vec3(kSx[k] * 0.5 * length, y, kSz[k] * 0.5 * width);
    }
  }
  return out;
}

std::array<Vec2, 4> Box3D::bev_corners() const {
  const auto c = corners();
  return {Vec2(c[0].x(), c[0].z()), Vec2(c[1].x(), c[1].z()), Vec2(c[2].x(), c[2].z()),
          Vec2(c[3].x(), c[3].z())};
}

bool Box3D::valid() const {
  return center.allFinite() && std::isfinite(yaw) && length > 0 && width > 0 && height > 0 &&
         std::isfinite(length * width * height);
}

Vec4 project_box(const Box3D& box, const Mat34& P, int width, int height, double z_near) {
  static constexpr int kEdges[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                        {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  const auto corners = box.corners();
  double x1 = std::numeric_limits<double>::infinity(), y1 = x1;
  double x2 = -x1, y2 = -x1;
  bool any = false;
  auto add = [&](const Vec3& X) {
    const Vec3 p = P * X.homogeneous();
    const double u = p.x() / p.z(), v = p.y() / p.z();
    x1 = std::min(x1, u), y1 = std::min(y1, v), x2 = std::max(x2, u), y2 = std::max(y2, v);
    any = true;
  };
  for (const auto& e : kEdges) {
    const Vec3& a = corners[e[0]];
    const Vec3& b = corners[e[1]];
    const bool a_in = a.z() >= z_near, b_in = b.z() >= z_near;
    if (a_in) add(a);
    if (b_in) add(b);
    if (a_in != b_in) add(a + (z_near - a.z()) / (b.z() - a.z()) * (b - a));  // cut at near plane
  }
  if (!any) return Vec4::Constant(std::numeric_limits<double>::quiet_NaN());
  if (width > 0 && height > 0) {
    x1 = std::clamp(x1, 0.0, width - 1.0), x2 = std::clamp(x2, 0.0, width - 1.0);
    y1 = std::clamp(y1, 0.0, height - 1.0), y2 = std::clamp(y2, 0.0, height - 1.0);
  }
  return Vec4(x1, y1, x2, y2);
}

}  // namespace twistslam::geometry
