#include "objects/association.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "geometry/box_overlap.hpp"

namespace twistslam::objects {

AssociationMetric association_metric_from_string(const std::string& name) {
  if (name == "giou_3d") return AssociationMetric::kGiou3d;
  if (name == "iou_bev") return AssociationMetric::kIouBev;
  if (name == "centre_distance") return AssociationMetric::kCentreDistance;
  throw std::invalid_argument("unknown association metric '" + name +
                              "' (valid: giou_3d, iou_bev, centre_distance)");
}

const char* to_string(AssociationMetric metric) {
  switch (metric) {
    case AssociationMetric::kGiou3d: return "giou_3d";
    case AssociationMetric::kIouBev: return "iou_bev";
    case AssociationMetric::kCentreDistance: return "centre_distance";
  }
  return "unknown";
}

Eigen::MatrixXd association_cost(const std::vector<geometry::Box3D>& tracks,
                                 const std::vector<int>& track_classes,
                                 const std::vector<geometry::Box3D>& detections,
                                 const std::vector<int>& detection_classes,
                                 AssociationMetric metric) {
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd cost(tracks.size(), detections.size());
  for (size_t i = 0; i < tracks.size(); ++i) {
    for (size_t j = 0; j < detections.size(); ++j) {
      if (track_classes[i] != detection_classes[j]) {
        cost(i, j) = inf;
        continue;
      }
      const auto& a = tracks[i];
      const auto& b = detections[j];
      switch (metric) {
        case AssociationMetric::kGiou3d: cost(i, j) = 1.0 - geometry::giou_3d(a, b); break;
        case AssociationMetric::kIouBev: {
          // boxes that do not overlap are never the same object under this metric, whatever
          // the gate (1 - IoU saturates at 1 and cannot rank them)
          const double iou = geometry::iou_bev(a, b);
          cost(i, j) = iou > 0 ? 1.0 - iou : inf;
          break;
        }
        case AssociationMetric::kCentreDistance: cost(i, j) = (a.center - b.center).norm(); break;
      }
    }
  }
  return cost;
}

Mat4 turned_around(const Mat4& T_w_o) {
  Mat4 T = T_w_o;
  T.block<3, 1>(0, 0) *= -1.0;  // x and z axes flip: rotation by pi about the box's y axis
  T.block<3, 1>(0, 2) *= -1.0;
  return T;
}

bool heading_flipped(const Mat4& T_w_detected, const Mat4& T_w_reference) {
  return T_w_detected.block<3, 1>(0, 0).dot(T_w_reference.block<3, 1>(0, 0)) < 0.0;
}

bool quarter_turned(const Mat4& T_w_detected, const Mat4& T_w_reference) {
  // x (length) and z (width) of a box frame span its ground plane (y is down)
  const double along = T_w_detected.block<3, 1>(0, 0).dot(T_w_reference.block<3, 1>(0, 0));
  const double across = T_w_detected.block<3, 1>(0, 0).dot(T_w_reference.block<3, 1>(0, 2));
  return std::abs(across) > std::abs(along);
}

}  // namespace twistslam::objects
