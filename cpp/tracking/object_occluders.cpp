// Occlusion in the visual object tracking: the optical flow and the instance masks follow the
// image, so when a car passes in front of a farther one, the far cluster's points project onto
// the near car's mask and the association by mask overlap gives it that mask. The LiDAR tells
// the two surfaces apart (not in the paper; urban seed 0 with the classical detector: a parked
// car's 6-point cluster at 51 m took an oncoming car's mask at 38 m by overlap, grew its points
// there and held it for 20 frames while no cluster started on that car).
#include <algorithm>
#include <vector>

#include "tracking/instance_pixels.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
using detail::median_value;
using detail::transform;

const std::vector<double>* ObjectTracker::mask_lidar_depths(int instance) const {
  if (!scan_ || instances_.empty()) return nullptr;
  if (!mask_lidar_depths_ready_) {
    for (Eigen::Index i = 0; i < scan_->rows(); ++i) {  // one pass over the scan
      const Vec3 p = scan_->row(i).transpose();
      if (!(p.z() > 0.1)) continue;
      const Vec2 uv = camera_.project(p);
      if (!camera_.in_image(uv)) continue;
      const int id = pixel_value(instances_, uv);
      if (id > 0) mask_lidar_depths_[id].push_back(p.z()), mask_lidar_points_[id].push_back(p);
    }
    mask_lidar_depths_ready_ = true;
  }
  static const std::vector<double> kNone;
  const auto it = mask_lidar_depths_.find(instance);
  return it == mask_lidar_depths_.end() ? &kNone : &it->second;
}

void ObjectTracker::release_occluding_instances(const std::vector<int>& clusters, const std::vector<Mat4>& T_w_o,
                                                const Frame& frame,
                                                const std::vector<objects::ClusterInstanceEvidence>& evidence,
                                                std::vector<int>* instances) const {
  const double ratio = lidar_options_.mask_max_depth_ratio;
  // the mask's depth from the LiDAR: its stereo keypoints are where stereo fails (an
  // occluding edge's corners take the nearer surface's depth; a far car's often have none),
  // and with them the test cost the camera alone (ten sequences: RPE_r 0.184 -> 0.190 deg/m)
  if (!(ratio > 0) || instances_.empty() || !scan_) return;
  // the clusters given their instance by overlap alone, and their points' depths on it
  for (size_t j = 0; j < clusters.size(); ++j) {
    const int instance = (*instances)[j];
    if (instance <= 0 || evidence[j].shared.count(instance) >= options_.min_shared_points) continue;
    const Mat4 T_c_o = frame.T_c_w * T_w_o[j];
    std::vector<double> depths;
    for (const objects::ObjectPoint& p : clusters_[clusters[j]].points) {
      const Vec3 X_c = transform(T_c_o, p.X_o);
      if (X_c.z() <= 0.1) continue;
      const Vec2 uv = camera_.project(X_c);
      if (camera_.in_image(uv) && pixel_value(instances_, uv) == instance) depths.push_back(X_c.z());
    }
    const std::vector<double>* returns = mask_lidar_depths(instance);
    if (depths.empty() || static_cast<int>(returns->size()) < lidar_options_.mask_min_returns)
      continue;  // nothing to compare
    const double cluster_depth = median_value(depths), mask_depth = median_value(*returns);
    if (cluster_depth > ratio * mask_depth || mask_depth > ratio * cluster_depth) (*instances)[j] = -1;
  }
}

}  // namespace twistslam::tracking
