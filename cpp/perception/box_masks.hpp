#pragma once
// Panoptic labels without network weights: instance masks from 3D boxes, road from LiDAR
// (what the system runs on real KITTI, python/twistslam/perception/panoptic_from_boxes.py).
// For each box the LiDAR points inside it, minus the ground under it, are projected into the
// left image and their convex hull is filled; boxes are drawn far to near so a nearer object
// covers a farther one. Road: a RANSAC plane through the low points; the points within a band
// of it mark the cells of a bird's-eye grid, and a pixel is road when its ray meets the plane
// in a marked cell (a LiDAR ring is many pixels apart near the car, so dilating the projected
// points alone leaves gaps). Everything else keeps the `unknown` class.
#include <cstdint>
#include <optional>
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::perception {

// Measured values and their reasons: BoxMaskConfig in panoptic_from_boxes.py.
struct BoxMaskOptions {
  double low_point_below_camera_m = 1.0;  // m below the camera (+y) for a ground candidate
  double plane_fit_threshold_m = 0.1;     // m, RANSAC inlier distance of the plane fit
  double ground_band_m = 0.1;             // m from the plane for a point to mark a road cell
  double hull_ground_clearance_m = 0.1;   // m above the plane for a box point to join a hull
  double road_cell_m = 0.5;               // m, side of a bird's-eye road cell
  int road_dilation_cells = 1;            // 4-neighbour dilations of the road grid
  double road_max_range_m = 40.0;         // m, farthest road cell (and half the grid's width)
  int min_box_points = 3;                 // inside points a box needs for a mask
};

// Checks every field; std::invalid_argument naming the field when one is out of range.
void validate(const BoxMaskOptions& options);

// One box in the rectified camera frame: KITTI's object frame (x along the length, y down,
// z across), centred; yaw = rotation_y.
struct MaskBox {
  Vec3 centre = Vec3::Zero();  // m, geometric centre (not KITTI's bottom centre)
  double length = 0, width = 0, height = 0, yaw = 0;  // m, rad
  std::int32_t class_id = 0;     // written into class_id under the mask
  std::int32_t instance_id = 0;  // written into instance_id under the mask
};

// Plane (n, d), n . X + d = 0 with n pointing up (towards -y), through the points lower than
// `low_point_below_camera_m`; nullopt with fewer than 3 of them.
std::optional<Vec4> ground_plane(const Points3& points_c, const BoxMaskOptions& options);

struct BoxMasks {
  int height = 0, width = 0;
  std::vector<std::int32_t> class_id;     // row-major (height, width)
  std::vector<std::int32_t> instance_id;  // 0 where no box
  std::optional<Vec4> plane;              // the ground plane, when one was fitted
};

// Labels of one image of size (height, width) from its LiDAR points (camera frame; rows with
// a non-finite coordinate are ignored) and boxes, with P the left image's 3x4 projection.
// Pixels start as `unknown_id`; road pixels become `road_id`. std::invalid_argument on a
// non-positive image size or invalid options.
BoxMasks masks_from_boxes(const Points3& points_c, const std::vector<MaskBox>& boxes,
                          const Mat34& P, int height, int width, const BoxMaskOptions& options,
                          std::int32_t unknown_id, std::int32_t road_id);

}  // namespace twistslam::perception
