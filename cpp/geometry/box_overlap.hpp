#pragma once
// Overlap of boxes: axis-aligned image boxes, bird-view rotated rectangles (exact convex
// polygon clipping) and 3D boxes (bird-view intersection times vertical overlap), as the
// KITTI evaluation measures them.
#include <vector>

#include "geometry/box3d.hpp"

namespace twistslam::geometry {

// Area of a simple polygon (shoelace), positive when counter-clockwise.
double polygon_signed_area(const std::vector<Vec2>& poly);

// Intersection of two convex polygons (Sutherland-Hodgman); either orientation accepted.
std::vector<Vec2> convex_polygon_intersection(std::vector<Vec2> subject, std::vector<Vec2> clip);

// Image boxes [x1, y1, x2, y2]; IoU 0 when either is empty or invalid.
double iou_2d(const Vec4& a, const Vec4& b);

double bev_intersection_area(const Box3D& a, const Box3D& b);
double iou_bev(const Box3D& a, const Box3D& b);
double iou_3d(const Box3D& a, const Box3D& b);

}  // namespace twistslam::geometry
