#pragma once
// Options of the LiDAR fusion into the visual object tracking (paper sec. "Injecting LiDAR
// scans", eq. 5-9): 3D detections associated with clusters give the canonical pose, the size
// and the drift-free twist e_det; consecutive object scans registered by GICP give e_reg.
// The defaults and their measured reasons are in python/twistslam/config_lidar_objects.py
// (tests/python/test_config.py checks they are equal key for key).

namespace twistslam::tracking {

struct ObjectLidarOptions {
  bool use_detections = true;              // associate the frame's 3D detections with clusters
  double detection_max_distance_m = 2.0;   // box to cluster (paper: 2 m)
  double detection_min_score = -1e9;       // detections below this are ignored
  bool canonical_pose = true;              // the first associated box sets the object frame
  double heading_from_motion_m = 3.0;      // travelled this far, a box frame facing backwards turns
  // e_det and the detection pose prior in the object window (optim/visual_object_window.hpp)
  bool use_detection_twist = true;
  double det_sigma_translation = 0.2;      // m/frame
  double det_sigma_rotation = 0.05;        // rad/frame
  bool use_detection_pose = true;
  double det_pose_sigma_translation = 0.3; // m
  double det_pose_sigma_rotation = 0.1;    // rad
  double huber_det = 2.0;                  // sigmas
};

template <typename Visit>
void for_each_option(ObjectLidarOptions& o, Visit&& visit) {
  visit("use_detections", o.use_detections, 0, 1);
  visit("detection_max_distance_m", o.detection_max_distance_m, 0.0, 1000.0);
  visit("detection_min_score", o.detection_min_score, -1e9, 1e9);
  visit("canonical_pose", o.canonical_pose, 0, 1);
  visit("heading_from_motion_m", o.heading_from_motion_m, 0.0, 1e6);
  visit("use_detection_twist", o.use_detection_twist, 0, 1);
  visit("det_sigma_translation", o.det_sigma_translation, 1e-6, 100.0);
  visit("det_sigma_rotation", o.det_sigma_rotation, 1e-6, 10.0);
  visit("use_detection_pose", o.use_detection_pose, 0, 1);
  visit("det_pose_sigma_translation", o.det_pose_sigma_translation, 1e-6, 1000.0);
  visit("det_pose_sigma_rotation", o.det_pose_sigma_rotation, 1e-6, 10.0);
  visit("huber_det", o.huber_det, 0.0, 1000.0);  // 0: no loss
}

}  // namespace twistslam::tracking
