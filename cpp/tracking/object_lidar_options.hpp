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
  // a cluster's first box must fall on its instance: of the box's LiDAR returns landing on
  // object masks, the most on the cluster's own (decided from this many returns; 0: off)
  int box_instance_min_returns = 5;
  double box_instance_max_distance_m = 6.0;  // ... up to this far (a box on its instance: its car)
  // the same for a canonical vehicle track's later boxes (its visual motion may have left its
  // car's boxes beyond detection_max_distance_m)
  bool own_mask_boxes_for_canonical = true;
  // a cluster's instance taken by mask overlap alone must lie within this depth ratio of the
  // mask's LiDAR returns (a car passing in front of a far cluster; 0: off), and a new cluster's
  // stereo points as well (wrong matches)
  double mask_max_depth_ratio = 1.3;
  int mask_min_returns = 1;                // fewer LiDAR returns on a mask: no depth test
  // the LiDAR returns on an instance's own mask (ObjectTracker::instance_returns): a new (or
  // re-seeded) cluster with too few stereo points places its other keypoints at their depth,
  bool instance_lidar_depth = true;
  double instance_lidar_max_depth_m = 30;  // ... for masks whose returns' median is this near
  // and a stereo point of the instance farther than this fraction from their local depth joins
  // no cluster (0: off)
  double instance_lidar_max_depth_error = 0.2;
  // vehicle keypoints' depth from the returns on their own mask (median within 8 px, or a
  // local plane): 0 off, 1 those without stereo, 2 also stereo ones farther than
  // instance_lidar_max_depth_error from it, 3 every one with returns near it; within
  // keypoint_lidar_max_depth_m; with keypoint_lidar_agreement > 0 only where plane and median
  // agree within that fraction. Off: measured, not yet a gain in every case (see the Python
  // config and docs/visual_objects.md)
  int keypoint_lidar_depth = 0;
  double keypoint_lidar_max_depth_m = 80;
  bool keypoint_lidar_plane = false;
  double keypoint_lidar_agreement = 0;
  double detection_min_score = -1e9;       // detections below this are ignored
  bool canonical_pose = true;              // the first associated box sets the object frame
  double heading_from_motion_m = 1.5;      // travelled this far, a box frame facing backwards turns
  double heading_motion_min_sigmas = 5.0;  // ... and this many standard errors of the distance
  double heading_motion_max_angle_deg = 45;  // ... along the frame's x axis (a car drives along it)
  bool heading_from_votes = true;          // until then, it faces the way most of its boxes do
  // ... and its own returns' height profile votes too (the hood-minus-trunk gap,
  // detection/front_profile.hpp): its views that span at least front_profile_min_span of its
  // length, once their mean is at least front_profile_min_sigmas standard errors and
  // front_profile_min_difference_m from 0 with front_profile_min_views views, one vote each
  bool heading_from_profile = true;
  int front_profile_min_views = 5;
  double front_profile_min_span = 0.9;
  double front_profile_min_sigmas = 3.0;
  double front_profile_min_difference_m = 0.1;
  // a prior-length box whose length axis lies at least this far from the line of sight saw a
  // side (its axis is the car's); nearer it, the axis was laid away from a face seen end-on
  double side_view_min_angle_deg = 60;
  // a box without its own heading (mod pi) votes with the one a parked car has on its side of
  // the camera's lane: +1 right-hand traffic (a car on the right faces the camera's travel,
  // one on the left faces it), -1 left-hand traffic, 0 no vote
  int road_side_heading = 1;
  double road_side_min_lateral_m = 2.0;     // a box nearer the camera's path than this: no vote
  double road_side_max_lateral_m = 8.0;     // ... nor one farther aside (off the camera's road)
  double road_side_max_angle_deg = 30.0;    // ... nor one whose axis is farther off the travel
  // a cluster whose rows turned faster than this (mean over its rows before its first box,
  // deg/frame) made the turn up: its first box levels them to its heading (0: never)
  double cluster_turn_max_deg_per_frame = 5.0;
  // the canonical frame re-anchored to the mean offset of all its boxes (objects/box_offset.hpp)
  bool refine_canonical = true;
  double refine_min_range_m = 5.0;         // box weight 1 / max(range, this)^2
  double refine_min_shift_m = 0.01;        // smaller offsets leave the frame as it is
  double refine_min_turn_rad = 0.002;      // ... and smaller turns
  double refine_min_agreement = 0.6;       // fraction of the boxes within 1 m / 15 deg of the mean
  int refine_min_boxes = 5;                // fewer boxes in the track: the first box's frame stays
  // a track whose origin lies in another's box (grown by this) this frame and that has fewer
  // boxes is not reported in it (two clusters on one car); < 0: never
  double duplicate_margin_m = 0.3;
  // a canonical track without a box this frame is not reported when at least see_through_min_rays
  // returns (0: off), and see_through_ratio times those inside, lie beyond its box (shrunk by
  // see_through_shrink_m) on rays crossing it (objects/box_free_space.hpp)
  // a new canonical track's backcast from the boxes no track took in the frames before it
  // (objects/box_chain.hpp): at most this many frames (0: off), and the chain's gates (m)
  int backfill_frames = 10;
  double backfill_first_gate_m = 3.0;
  double backfill_gate_m = 1.0;
  double backfill_ambiguity_m = 1.0;
  int see_through_min_rays = 10;
  double see_through_ratio = 3.0;
  double see_through_shrink_m = 0.3;
  // a camera-only vehicle track whose points lie nearer than the LiDAR returns around them (on
  // its mask), by a median over its rows of more than lidar_check_max_ratio of their depth
  // and lidar_check_min_offset_m, is not reported (0: off); rows with at least
  // lidar_check_min_returns returns on the mask and lidar_check_min_points points compared
  // count, and lidar_check_min_rows of them decide
  double lidar_check_max_ratio = 0.04;
  double lidar_check_min_offset_m = 1.5;
  // the other side: points beyond the returns by a median of more than lidar_check_max_far_ratio
  // of their depth and lidar_check_min_far_offset_m (0: off)
  double lidar_check_max_far_ratio = 0.08;
  double lidar_check_min_far_offset_m = 3.0;
  int lidar_check_min_rows = 5;
  int lidar_check_min_returns = 5;
  int lidar_check_min_points = 3;
  // the final rows of a camera-only vehicle track farther than far_lidar_align_min_depth_m
  // move along their lines of sight by the median, over its rows, of the LiDAR returns' depth
  // over its points' (0: off); a row's median counts within far_lidar_align_max_ratio of 1,
  // far_lidar_align_min_rows of them decide, and the scale grows in over far_lidar_align_ramp_m
  // (object_lidar_align.cpp)
  double far_lidar_align_min_depth_m = 30.0;
  double far_lidar_align_ramp_m = 15.0;
  double far_lidar_align_max_ratio = 0.15;
  int far_lidar_align_min_rows = 3;
  // ... a nearer move stops where the track's origin meets this quantile of its returns'
  // depth (the face the LiDAR sees; tracking/object_lidar_align.hpp, far_surface_floor)
  bool far_lidar_align_surface_floor = true;
  double far_lidar_align_surface_quantile = 0.1;
  double far_lidar_align_surface_margin = 0.01;  // ... less this fraction of the origin's depth
  // ... and an origin already in front of that face moves onto it (by at most
  // far_lidar_align_max_ratio; tracking/object_lidar_align.hpp, far_align_scale)
  bool far_lidar_align_surface_lift = true;
  // ... and a camera-only vehicle row nearer than far_lidar_align_min_depth_m whose origin lies
  // in front of the face its own mask's returns measured (the same quantile, less the margin)
  // moves onto it, by at most far_lidar_align_max_ratio; not where the mask reaches the image's
  // border, and only rows with a face of their own (object_lidar_align.cpp,
  // lift_near_rows_onto_their_face; off with far_lidar_align_min_depth_m 0)
  bool near_lidar_surface_lift = true;
  int near_lidar_surface_window_rows = 7;  // ... the running median of this many rows' floors
  // the rows of a camera-only free-link track (a pedestrian, a cyclist) farther than
  // far_lidar_align_free_min_depth_m move along their lines of sight each by its own ratio, the
  // running median over far_lidar_align_free_window_rows rows around it (0: off): a thin body's
  // drift grows row by row, which one track-wide ratio cannot undo (object_lidar_align.cpp)
  int far_lidar_align_free_window_rows = 7;
  double far_lidar_align_free_min_depth_m = 25.0;
  // ... each row's ratio is its mask's returns' median depth over its origin's depth (off: its
  // points' against the returns around them, as the vehicles'), and a row whose running median
  // lies beyond far_lidar_align_max_ratio of 1 is not reported (off: it stays where it is)
  bool far_lidar_align_free_from_origin = true;
  bool far_lidar_align_free_hide_beyond = true;
  // a camera-only vehicle's far rows (beyond far_lidar_align_min_depth_m) whose origin lies more
  // than this beyond the median depth of their mask's returns, by their own measure and by the
  // running median over far_lidar_align_behind_window_rows rows, move nearer by the smaller
  // excess (0: off; tracking/object_lidar_align.cpp, pull_far_rows_to_their_returns). 1.5 m: on
  // 8 urban sequences (both flows, 3689 far rows) the rows 1-2 m beyond all lay on their cars
  // (109), those 2-3.5 m beyond 9 of 18 (docs/visual_objects.md, "Far rows behind their returns")
  double far_lidar_align_max_behind_m = 1.5;
  int far_lidar_align_behind_window_rows = 7;
  // point-extent boxes (Detection::point_extent) laid from their near end, the car's length
  // from this quantile of theirs (off: every box as an estimate, the median length)
  bool point_extent_lengths = false;
  double point_extent_length_quantile = 0.9;
  // e_det and the detection pose prior in the object window (optim/visual_object_window.hpp)
  bool use_detection_twist = true;
  double det_sigma_translation = 0.2;      // m/frame
  double det_sigma_rotation = 0.05;        // rad/frame
  bool use_detection_pose = true;
  double det_pose_sigma_translation = 0.3; // m
  double det_pose_sigma_rotation = 0.1;    // rad
  double huber_det = 2.0;                  // sigmas
  double det_sigma_reference_range_m = 20.0;  // m; farther boxes: e_det sigmas x range / it (0: off)
  // e_reg: GICP between consecutive object scans (the points of the frame's scan inside the
  // canonical box, enlarged), registration/gicp.hpp
  bool use_registration = true;
  double scan_margin_m = 0.3;              // the box grows by this on each side (not below)
  double scan_ground_clearance_m = 0.15;   // points this close above the box's bottom are road
  int min_scan_points = 30;                // fewer: no scan this frame
  double reg_max_rmse_m = 0.3;             // a registration with a larger residual is refused
  double reg_min_inlier_fraction = 0.5;    // ... or fewer of the scan's points matched
  double reg_sigma_translation = 0.03;     // m/frame (fixed, without reg_sigma_from_information)
  double reg_sigma_rotation = 0.005;       // rad/frame
  // per-registration sigmas: scale * the marginal standard deviation of GICP's inverse
  // information (at the object's centre, in the link's rotation), at least the floors
  bool reg_sigma_from_information = true;
  double reg_information_scale_translation = 1.0;
  double reg_information_scale_rotation = 0.5;
  double reg_min_sigma_translation = 0.01;  // m/frame
  double reg_min_sigma_rotation = 0.001;    // rad/frame
  // e_reg weighs each direction by GICP's covariance along it (scaled and floored as above),
  // not every direction by the largest sigma: a face seen alone pins the step across it
  // (planar-link objects only: a rigid scan)
  bool reg_full_covariance = true;
  double huber_reg = 2.0;                  // sigmas
  // e_det, e_reg and the box prior in the keyframe BA too, relative to its cameras, whenever
  // local_ba.dynamic_objects puts the objects there (each as its use_* switch above allows)
  bool keyframe_ba_terms = true;
  // the final smoothing of a track with LiDAR terms (boxes, registered scans): its keypoints'
  // reprojection sigmas times this (ObjectTrackingOptions::final_smoothing)
  double smoothing_keypoint_sigma_scale = 5.0;
  // in a frame with 3D boxes, ObjectTrackingOptions::instance_border_px is this instead (a box
  // places its car, and a far car's corners along nearer cars are what it has left)
  double instance_border_px = 0.0;
  // ... and ObjectTrackingOptions::depth_fill_below_points this (0: a box places its car; the
  // filled depths of far cars' masks seeded canonical ghosts)
  int depth_fill_below_points = 0;
};

template <typename Visit>
void for_each_option(ObjectLidarOptions& o, Visit&& visit) {
  visit("use_detections", o.use_detections, 0, 1);
  visit("instance_border_px", o.instance_border_px, 0.0, 50.0);
  visit("depth_fill_below_points", o.depth_fill_below_points, 0, 100000);
  visit("detection_max_distance_m", o.detection_max_distance_m, 0.0, 1000.0);
  visit("box_instance_min_returns", o.box_instance_min_returns, 0, 1000000);
  visit("box_instance_max_distance_m", o.box_instance_max_distance_m, 0.0, 1000.0);
  visit("own_mask_boxes_for_canonical", o.own_mask_boxes_for_canonical, 0, 1);
  visit("mask_max_depth_ratio", o.mask_max_depth_ratio, 0.0, 1000.0);  // 0: off, else >= 1
  visit("mask_min_returns", o.mask_min_returns, 1, 1000000);
  visit("instance_lidar_depth", o.instance_lidar_depth, 0, 1);
  visit("instance_lidar_max_depth_m", o.instance_lidar_max_depth_m, 0.0, 10000.0);
  visit("instance_lidar_max_depth_error", o.instance_lidar_max_depth_error, 0.0, 10.0);
  visit("keypoint_lidar_depth", o.keypoint_lidar_depth, 0, 3);
  visit("keypoint_lidar_max_depth_m", o.keypoint_lidar_max_depth_m, 0.0, 10000.0);
  visit("keypoint_lidar_plane", o.keypoint_lidar_plane, 0, 1);
  visit("keypoint_lidar_agreement", o.keypoint_lidar_agreement, 0.0, 10.0);
  visit("detection_min_score", o.detection_min_score, -1e9, 1e9);
  visit("canonical_pose", o.canonical_pose, 0, 1);
  visit("heading_from_motion_m", o.heading_from_motion_m, 0.0, 1e6);
  visit("heading_motion_min_sigmas", o.heading_motion_min_sigmas, 0.0, 1e6);
  visit("heading_motion_max_angle_deg", o.heading_motion_max_angle_deg, 0.0, 90.0);
  visit("heading_from_votes", o.heading_from_votes, 0, 1);
  visit("heading_from_profile", o.heading_from_profile, 0, 1);
  visit("front_profile_min_views", o.front_profile_min_views, 2, 100000);
  visit("front_profile_min_span", o.front_profile_min_span, 0.0, 1.0);
  visit("front_profile_min_sigmas", o.front_profile_min_sigmas, 0.0, 100.0);
  visit("front_profile_min_difference_m", o.front_profile_min_difference_m, 0.0, 10.0);
  visit("side_view_min_angle_deg", o.side_view_min_angle_deg, 0.0, 90.0);
  visit("road_side_heading", o.road_side_heading, -1, 1);
  visit("road_side_min_lateral_m", o.road_side_min_lateral_m, 0.0, 1000.0);
  visit("road_side_max_lateral_m", o.road_side_max_lateral_m, 0.0, 1000.0);
  visit("road_side_max_angle_deg", o.road_side_max_angle_deg, 0.0, 90.0);
  visit("cluster_turn_max_deg_per_frame", o.cluster_turn_max_deg_per_frame, 0.0, 180.0);
  visit("refine_canonical", o.refine_canonical, 0, 1);
  visit("refine_min_range_m", o.refine_min_range_m, 0.01, 1000.0);
  visit("refine_min_shift_m", o.refine_min_shift_m, 0.0, 100.0);
  visit("refine_min_turn_rad", o.refine_min_turn_rad, 0.0, 10.0);
  visit("refine_min_agreement", o.refine_min_agreement, 0.0, 1.0);
  visit("refine_min_boxes", o.refine_min_boxes, 2, 1000000);
  visit("duplicate_margin_m", o.duplicate_margin_m, -1.0, 10.0);
  visit("backfill_frames", o.backfill_frames, 0, 1000);
  visit("backfill_first_gate_m", o.backfill_first_gate_m, 0.0, 100.0);
  visit("backfill_gate_m", o.backfill_gate_m, 0.0, 100.0);
  visit("backfill_ambiguity_m", o.backfill_ambiguity_m, 0.0, 100.0);
  visit("see_through_min_rays", o.see_through_min_rays, 0, 1000000);
  visit("see_through_ratio", o.see_through_ratio, 0.0, 1e6);
  visit("see_through_shrink_m", o.see_through_shrink_m, 0.0, 10.0);
  visit("lidar_check_max_ratio", o.lidar_check_max_ratio, 0.0, 10.0);
  visit("lidar_check_min_offset_m", o.lidar_check_min_offset_m, 0.0, 1000.0);
  visit("lidar_check_max_far_ratio", o.lidar_check_max_far_ratio, 0.0, 1.0);
  visit("lidar_check_min_far_offset_m", o.lidar_check_min_far_offset_m, 0.0, 1000.0);
  visit("lidar_check_min_rows", o.lidar_check_min_rows, 1, 1000000);
  visit("lidar_check_min_returns", o.lidar_check_min_returns, 1, 1000000);
  visit("lidar_check_min_points", o.lidar_check_min_points, 1, 1000000);
  visit("far_lidar_align_min_depth_m", o.far_lidar_align_min_depth_m, 0.0, 1000.0);
  visit("far_lidar_align_ramp_m", o.far_lidar_align_ramp_m, 0.0, 1000.0);
  visit("far_lidar_align_max_ratio", o.far_lidar_align_max_ratio, 0.0, 1.0);
  visit("far_lidar_align_min_rows", o.far_lidar_align_min_rows, 1, 1000000);
  visit("far_lidar_align_surface_floor", o.far_lidar_align_surface_floor, 0, 1);
  visit("far_lidar_align_surface_quantile", o.far_lidar_align_surface_quantile, 0.0, 1.0);
  visit("far_lidar_align_surface_margin", o.far_lidar_align_surface_margin, 0.0, 1.0);
  visit("far_lidar_align_surface_lift", o.far_lidar_align_surface_lift, 0, 1);
  visit("near_lidar_surface_lift", o.near_lidar_surface_lift, 0, 1);
  visit("near_lidar_surface_window_rows", o.near_lidar_surface_window_rows, 1, 1000000);
  visit("far_lidar_align_free_window_rows", o.far_lidar_align_free_window_rows, 0, 1000000);
  visit("far_lidar_align_free_min_depth_m", o.far_lidar_align_free_min_depth_m, 0.0, 1000.0);
  visit("far_lidar_align_free_from_origin", o.far_lidar_align_free_from_origin, 0, 1);
  visit("far_lidar_align_free_hide_beyond", o.far_lidar_align_free_hide_beyond, 0, 1);
  visit("far_lidar_align_max_behind_m", o.far_lidar_align_max_behind_m, 0.0, 1000.0);
  visit("far_lidar_align_behind_window_rows", o.far_lidar_align_behind_window_rows, 1, 1000000);
  visit("point_extent_lengths", o.point_extent_lengths, 0, 1);
  visit("point_extent_length_quantile", o.point_extent_length_quantile, 0.0, 1.0);
  visit("use_detection_twist", o.use_detection_twist, 0, 1);
  visit("det_sigma_translation", o.det_sigma_translation, 1e-6, 100.0);
  visit("det_sigma_rotation", o.det_sigma_rotation, 1e-6, 10.0);
  visit("use_detection_pose", o.use_detection_pose, 0, 1);
  visit("det_pose_sigma_translation", o.det_pose_sigma_translation, 1e-6, 1000.0);
  visit("det_pose_sigma_rotation", o.det_pose_sigma_rotation, 1e-6, 10.0);
  visit("huber_det", o.huber_det, 0.0, 1000.0);  // 0: no loss
  visit("det_sigma_reference_range_m", o.det_sigma_reference_range_m, 0.0, 1000.0);
  visit("use_registration", o.use_registration, 0, 1);
  visit("scan_margin_m", o.scan_margin_m, 0.0, 100.0);
  visit("scan_ground_clearance_m", o.scan_ground_clearance_m, -10.0, 10.0);
  visit("min_scan_points", o.min_scan_points, 3, 1000000);
  visit("reg_max_rmse_m", o.reg_max_rmse_m, 1e-6, 100.0);
  visit("reg_min_inlier_fraction", o.reg_min_inlier_fraction, 0.0, 1.0);
  visit("reg_sigma_translation", o.reg_sigma_translation, 1e-6, 100.0);
  visit("reg_sigma_rotation", o.reg_sigma_rotation, 1e-6, 10.0);
  visit("reg_sigma_from_information", o.reg_sigma_from_information, 0, 1);
  visit("reg_information_scale_translation", o.reg_information_scale_translation, 1e-6, 1e6);
  visit("reg_information_scale_rotation", o.reg_information_scale_rotation, 1e-6, 1e6);
  visit("reg_min_sigma_translation", o.reg_min_sigma_translation, 1e-6, 100.0);
  visit("reg_min_sigma_rotation", o.reg_min_sigma_rotation, 1e-6, 10.0);
  visit("reg_full_covariance", o.reg_full_covariance, 0, 1);
  visit("huber_reg", o.huber_reg, 0.0, 1000.0);
  visit("keyframe_ba_terms", o.keyframe_ba_terms, 0, 1);
  visit("smoothing_keypoint_sigma_scale", o.smoothing_keypoint_sigma_scale, 0.01, 1000.0);
}

}  // namespace twistslam::tracking
