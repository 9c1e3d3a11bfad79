#include "perception/hull_fill.hpp"

#include <algorithm>
#include <cmath>

namespace twistslam::perception {
namespace {

double cross(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// x-interval of the convex polygon on the horizontal line y (false: the line misses it)
bool span_at(const std::vector<Vec2>& hull, double y, double* x_lo, double* x_hi) {
  double lo = INFINITY, hi = -INFINITY;
  const size_t n = hull.size();
  for (size_t i = 0; i < n; ++i) {
    const Vec2& a = hull[i];
    const Vec2& b = hull[(i + 1) % n];
    if (y < std::min(a.y(), b.y()) || y > std::max(a.y(), b.y())) continue;
    if (a.y() == b.y()) {  // a horizontal edge on the line: both its ends
      lo = std::min({lo, a.x(), b.x()});
      hi = std::max({hi, a.x(), b.x()});
      continue;
    }
    const double x = a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  *x_lo = lo;
  *x_hi = hi;
  return lo <= hi;
}

}  // namespace

std::vector<Vec2> convex_hull(std::vector<Vec2> points) {
  auto less = [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); };
  std::sort(points.begin(), points.end(), less);
  points.erase(std::unique(points.begin(), points.end()), points.end());
  const size_t n = points.size();
  if (n < 3) return points;
  std::vector<Vec2> hull(2 * n);
  size_t k = 0;
  for (size_t i = 0; i < n; ++i) {  // lower chain; a turn that is not strictly left pops
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (size_t i = n - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);  // the last point is the first
  return hull;
}

std::vector<PixelSpan> convex_hull_pixels(const std::vector<Vec2>& points, int height, int width) {
  std::vector<PixelSpan> spans;
  for (const Vec2& p : points)
    if (!p.allFinite()) return spans;
  const std::vector<Vec2> hull = convex_hull(points);
  if (hull.size() < 3) return spans;
  double y_min = INFINITY, y_max = -INFINITY;
  for (const Vec2& p : hull) {
    y_min = std::min(y_min, p.y());
    y_max = std::max(y_max, p.y());
  }
  // rows whose centre v + 0.5 lies in [y_min, y_max], clipped to the image: far boxes are a
  // few pixels, and a point near the camera plane can put a vertex 1e7 px away
  const int v0 = static_cast<int>(std::max(0.0, std::ceil(y_min - 0.5)));
  const int v1 = static_cast<int>(std::min(static_cast<double>(height) - 1, std::floor(y_max - 0.5)));
  constexpr double kEps = 1e-9;  // px: a centre on an edge is inside
  for (int v = v0; v <= v1; ++v) {
    double x_lo, x_hi;
    if (!span_at(hull, v + 0.5, &x_lo, &x_hi)) continue;
    const int u0 = static_cast<int>(std::max(0.0, std::ceil(x_lo - 0.5 - kEps)));
    const int u1 = static_cast<int>(std::min(static_cast<double>(width) - 1, std::floor(x_hi - 0.5 + kEps)));
    if (u0 <= u1) spans.push_back({v, u0, u1});
  }
  for (const Vec2& p : points) {
    const double u = std::floor(p.x()), v = std::floor(p.y());
    if (u < 0 || v < 0 || u >= width || v >= height) continue;
    spans.push_back({static_cast<int>(v), static_cast<int>(u), static_cast<int>(u)});
  }
  return spans;
}

}  // namespace twistslam::perception
