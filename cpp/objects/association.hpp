#pragma once
// Association costs between predicted track boxes and detections (lower is better), and the
// heading alignment of a detection to a track.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geometry/box3d.hpp"

namespace twistslam::objects {

enum class AssociationMetric {
  kGiou3d,          // 1 - GIoU of the 3D boxes, in [0, 2] (AB3DMOT's choice on KITTI)
  kIouBev,          // 1 - IoU of the bird-view rectangles, in [0, 1); no overlap: +inf
  kCentreDistance,  // distance of the box centres, m (the paper's 2 m rule)
};

// "giou_3d" | "iou_bev" | "centre_distance"; std::invalid_argument naming the valid ones.
AssociationMetric association_metric_from_string(const std::string& name);
const char* to_string(AssociationMetric metric);

// (tracks x detections) cost matrix; pairs of different classes get +infinity.
Eigen::MatrixXd association_cost(const std::vector<geometry::Box3D>& tracks,
                                 const std::vector<int>& track_classes,
                                 const std::vector<geometry::Box3D>& detections,
                                 const std::vector<int>& detection_classes,
                                 AssociationMetric metric);

// A box's pose turned by pi about its own vertical axis (the same box, the other heading).
Mat4 turned_around(const Mat4& T_w_o);

// True when the detection's forward axis (object x) points against the reference's: its
// heading differs by more than 90 degrees, so it is the same box seen with a flipped yaw.
bool heading_flipped(const Mat4& T_w_detected, const Mat4& T_w_reference);

// True when the detection's length axis lies closer to the reference's width axis than to
// its length axis (more than 45 degrees apart modulo pi): the box was fitted a quarter turn
// off, e.g. a partly hidden L-shape read as a car's rear.
bool quarter_turned(const Mat4& T_w_detected, const Mat4& T_w_reference);

}  // namespace twistslam::objects
