#include "geometry/box_overlap.hpp"

#include <algorithm>
#include <cmath>

namespace twistslam::geometry {
namespace {

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

void make_ccw(std::vector<Vec2>* poly) {
  if (polygon_signed_area(*poly) < 0) std::reverse(poly->begin(), poly->end());
}

// Keeps the part of `poly` on the left of the directed edge p -> q.
std::vector<Vec2> clip_half_plane(const std::vector<Vec2>& poly, const Vec2& p, const Vec2& q) {
  std::vector<Vec2> out;
  const Vec2 edge = q - p;
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const Vec2& cur = poly[i];
    const Vec2& nxt = poly[(i + 1) % n];
    const double s_cur = cross2(edge, cur - p), s_nxt = cross2(edge, nxt - p);
    if (s_cur >= 0) out.push_back(cur);
    if ((s_cur >= 0) != (s_nxt >= 0)) {
      const double t = s_cur / (s_cur - s_nxt);
      out.push_back(cur + t * (nxt - cur));
    }
  }
  return out;
}

}  // namespace

double polygon_signed_area(const std::vector<Vec2>& poly) {
  double twice = 0;
  for (size_t i = 0, n = poly.size(); i < n; ++i) twice += cross2(poly[i], poly[(i + 1) % n]);
  return 0.5 * twice;
}

std::vector<Vec2> convex_polygon_intersection(std::vector<Vec2> subject, std::vector<Vec2> clip) {
  make_ccw(&subject);
  make_ccw(&clip);
  for (size_t i = 0, n = clip.size(); i < n && !subject.empty(); ++i) {
    subject = clip_half_plane(subject, clip[i], clip[(i + 1) % n]);
  }
  return subject;
}

double iou_2d(const Vec4& a, const Vec4& b) {
  const double area_a = (a[2] - a[0]) * (a[3] - a[1]);
  const double area_b = (b[2] - b[0]) * (b[3] - b[1]);
  if (!(area_a > 0) || !(area_b > 0)) return 0.0;
  const double w = std::min(a[2], b[2]) - std::max(a[0], b[0]);
  const double h = std::min(a[3], b[3]) - std::max(a[1], b[1]);
  if (w <= 0 || h <= 0) return 0.0;
  const double inter = w * h;
  return inter / (area_a + area_b - inter);
}

double bev_intersection_area(const Box3D& a, const Box3D& b) {
  // Cheap reject: circumscribed circles apart.
  const double ra = 0.5 * std::hypot(a.length, a.width), rb = 0.5 * std::hypot(b.length, b.width);
  const double dx = a.center.x() - b.center.x(), dz = a.center.z() - b.center.z();
  if (dx * dx + dz * dz > (ra + rb) * (ra + rb)) return 0.0;
  const auto ca = a.bev_corners();
  const auto cb = b.bev_corners();
  const auto inter = convex_polygon_intersection({ca.begin(), ca.end()}, {cb.begin(), cb.end()});
  return inter.size() < 3 ? 0.0 : std::abs(polygon_signed_area(inter));
}

double iou_bev(const Box3D& a, const Box3D& b) {
  if (!a.valid() || !b.valid()) return 0.0;
  const double inter = bev_intersection_area(a, b);
  return inter / (a.length * a.width + b.length * b.width - inter);
}

double iou_3d(const Box3D& a, const Box3D& b) {
  if (!a.valid() || !b.valid()) return 0.0;
  const double top = std::max(a.center.y() - 0.5 * a.height, b.center.y() - 0.5 * b.height);
  const double bottom = std::min(a.center.y() + 0.5 * a.height, b.center.y() + 0.5 * b.height);
  if (bottom <= top) return 0.0;
  const double inter = bev_intersection_area(a, b) * (bottom - top);
  return inter / (a.volume() + b.volume() - inter);
}

std::vector<Vec2> convex_hull(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  const auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Vec2> hull(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {  // lower chain
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k - 1);  // the last point repeats the first
  return hull;
}

namespace {
// Area of the convex hull of both bird-view rectangles.
double bev_enclosing_area(const Box3D& a, const Box3D& b) {
  const auto ca = a.bev_corners();
  const auto cb = b.bev_corners();
  std::vector<Vec2> all(ca.begin(), ca.end());
  all.insert(all.end(), cb.begin(), cb.end());
  return std::abs(polygon_signed_area(convex_hull(std::move(all))));
}
}  // namespace

double giou_bev(const Box3D& a, const Box3D& b) {
  if (!a.valid() || !b.valid()) return -1.0;
  const double inter = bev_intersection_area(a, b);
  const double uni = a.length * a.width + b.length * b.width - inter;
  const double enclosing = bev_enclosing_area(a, b);
  return inter / uni - (enclosing - uni) / enclosing;
}

double giou_3d(const Box3D& a, const Box3D& b) {
  if (!a.valid() || !b.valid()) return -1.0;
  const double top_a = a.center.y() - 0.5 * a.height, bottom_a = a.center.y() + 0.5 * a.height;
  const double top_b = b.center.y() - 0.5 * b.height, bottom_b = b.center.y() + 0.5 * b.height;
  const double overlap_h = std::max(0.0, std::min(bottom_a, bottom_b) - std::max(top_a, top_b));
  const double span_h = std::max(bottom_a, bottom_b) - std::min(top_a, top_b);
  const double inter = overlap_h > 0 ? bev_intersection_area(a, b) * overlap_h : 0.0;
  const double uni = a.volume() + b.volume() - inter;
  const double enclosing = bev_enclosing_area(a, b) * span_h;
  return inter / uni - (enclosing - uni) / enclosing;
}

}  // namespace twistslam::geometry
