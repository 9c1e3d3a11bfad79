#pragma once
// The 2D convex hull of image points and the pixels it covers: the instance mask of an object
// from its LiDAR points projected into the image (box_masks.hpp).
#include <cstdint>
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::perception {

// Hull vertices counter-clockwise (in x right, y down: clockwise on screen), Andrew's
// monotone chain; duplicates and collinear points are dropped. Fewer than 3 distinct points
// come back as they are (sorted by x, then y). Non-finite points must be removed first.
std::vector<Vec2> convex_hull(std::vector<Vec2> points);

struct PixelSpan {
  int v = 0, u0 = 0, u1 = -1;  // pixels u0..u1 (inclusive) of row v
};

// The pixels (u, v) whose centre (u + 0.5, v + 0.5) lies in the convex hull of `points` (px),
// one span per row, and every pixel holding a point (pixel (u, v) covers [u, u + 1) x
// [v, v + 1)) as a span of one: sparse LiDAR puts most of an object's points on its hull, and
// about half of those fall in pixels whose centre is just outside it (75 % of one real KITTI
// car's points were covered by the centre test alone). Clipped to the (height, width) image.
// A hull of fewer than 3 vertices, or a non-finite point, gives no pixel.
std::vector<PixelSpan> convex_hull_pixels(const std::vector<Vec2>& points, int height, int width);

}  // namespace twistslam::perception
