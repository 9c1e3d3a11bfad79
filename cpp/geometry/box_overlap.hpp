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

// Convex hull (Andrew's monotone chain), counter-clockwise, no collinear points.
std::vector<Vec2> convex_hull(std::vector<Vec2> points);

// Generalized IoU (Rezatofighi et al. 2019): IoU - (C - U) / C with C the smallest enclosing
// convex region: the convex hull of both bird-view rectangles (times the union of the
// vertical extents in 3D). In [-1, 1]; unlike IoU it still ranks boxes that do not overlap
// by how far apart they are, which 3D multi-object trackers use as association cost.
// Degenerate boxes: -1.
double giou_bev(const Box3D& a, const Box3D& b);
double giou_3d(const Box3D& a, const Box3D& b);

}  // namespace twistslam::geometry
