#pragma once
// Options of the visual object tracking in the SLAM (paper sec. "Clusters creation" and
// "Dynamic object tracking", eq. 1-4): which classes become object clusters, their link,
// the flow-guided search, the twist LM and the cluster lifetime. The defaults and their
// measured reasons are in python/twistslam/config_visual_objects.py (tests/python/test_config.py
// checks they are equal key for key).
#include <vector>

namespace twistslam::tracking {

struct ObjectTrackingOptions {
  bool enabled = true;  // track the clusters of object_class_ids (needs instance masks)
  // a-priori dynamic classes that form object clusters (Cityscapes: person 24, rider 25, car
  // 26, truck 27, bus 28, caravan 29, trailer 30, train 31, motorcycle 32, bicycle 33)
  std::vector<int> object_class_ids{24, 25, 26, 27, 28, 29, 30, 31, 32, 33};
  // classes moving on the road: planar link (3 DoF); the other object classes are free
  std::vector<int> planar_class_ids{26, 27, 28, 29, 30, 31, 32, 33};
  int road_class_id = 7;            // the road cluster gives the planar link's normal
  double road_max_depth_m = 25;     // road keypoints farther than this do not join the plane fit
  // LiDAR returns on road pixels join the road plane fit (tracking/road_lidar_points.hpp);
  // off: the stereo road keypoints give the plane as well (figures in config_visual_objects.py)
  bool road_lidar_points = false;
  double road_lidar_max_depth_m = 25;  // m along the optical axis
  int road_lidar_border_px = 3;        // px: the whole (2 b + 1)^2 window must be road
  int road_lidar_max_points = 300;     // returns per keyframe (the plane's reservoir holds 5000)
  // the road plane from the road points of the keyframes within this distance (m) of the
  // newest one (0: of every keyframe; config_visual_objects.py has the figures)
  double road_plane_window_m = 25;
  double flow_radius_px = 4;        // search window around the flow-predicted position
  double projection_radius_px = 12; // ... around the motion-model projection (no flow)
  double refine_radius_px = 3;      // ... of the second pass, around the estimated pose
  int max_hamming = 50;             // bits
  int flow_max_hamming = 80;        // bits, for keypoints searched around the flow prediction
  int min_new_cluster_points = 10;  // stereo keypoints inside a new instance mask (free link)
  int min_new_planar_cluster_points = 6;  // ... of a planar-link class (3-DoF twist)
  // a vehicle instance with too few stereo points starts at its ground-contact depth
  // (tracking/ground_contact.hpp; needs the class image and the road plane)
  bool ground_contact = true;
  int min_contact_columns = 5;      // mask columns with road right below their lowest pixel
  double min_contact_fraction = 0.5; // ... and this fraction of the mask's columns
  double contact_depth_quantile = 0.5;  // of the columns' contact depths: the car's depth
  int min_contact_cluster_points = 4;   // keypoints a cluster placed by its contact needs
  double contact_height_m = 0.0;        // the contact rays meet the plane this far above the road
  // a vehicle instance with fewer stereo points than this (but at least depth_fill_min_points,
  // their median within depth_fill_max_depth_m) starts with its keypoints without stereo too,
  // each at the depth of its nearest stereo keypoint (tracking/stereo_depth_fill.hpp; 0: off)
  int depth_fill_below_points = 12;
  int depth_fill_min_points = 3;
  double depth_fill_max_depth_m = 30;
  double depth_fill_min_stereo_share = 0.15;  // of the mask's free keypoints
  // a keypoint this close (level-0 px, times its level's scale) to another instance's pixel
  // belongs to neither: its corner and stereo depth may be the occluder's (0: off)
  double instance_border_px = 3;
  int min_shared_points = 5;        // matched points an instance must share with a cluster
  double min_mask_overlap = 0.5;    // fraction of projected cluster points inside the mask
  int min_inliers = 6;              // inliers of the twist LM for a tracked frame
  // fewer keypoint matches than this: the flow-predicted pixels of the cluster's points seen
  // in the last frame join the twist LM (0: off; 1000, above max_points: every cluster)
  int flow_observations_below_matches = 1000;
  double flow_observations_min_depth_m = 20;  // ... when its origin lies at least this far (m)
  // nearer than that: fewer keypoint matches than this (0: off), too few for the twist LM
  int flow_observations_near_below_matches = 6;
  // ... each with the depth of a SAD scan at its pixel on its instance's pixels, when the scan
  // finds one (a stereo observation: it sees motion along the line of sight; else mono)
  bool flow_observations_stereo = true;
  // > 0: each flow-located pixel is refined by pyramidal Lucas-Kanade on the left images, from
  // the point's last pixel, started at the flow's pixel, and kept when it lands within this
  // many pixels of it (a dense flow's error would otherwise chain from frame to frame); 0: the
  // flow's pixel as it is. config_visual_objects.py has the measurements of all four
  double flow_observations_lk_max_px = 1.0;
  double max_step_m = 5.0;          // object motion per frame beyond this is no motion (a fit gone wrong)
  int max_misses = 5;               // frames without a valid twist before the track ends
  int reseed_after_misses = 1;      // failed frames before new points replace a cluster's (0: never)
  // a cluster never tracked since its birth reports its re-seeded rows only this near (m)
  double untracked_report_max_depth_m = 45;
  // ... and those its ground contact placed only this near (m; config.py says why)
  double untracked_contact_report_max_depth_m = 45;
  // ... and only when it lies within this (m per frame apart) of the cluster's previous row
  // (0: no test): consecutive re-seeds of one car that jump farther place it on different
  // surfaces (config.py says why)
  double untracked_reseed_max_jump_m = 3.5;
  // a re-seeded cluster whose velocity rests on fewer valid twists than this is re-born at its
  // new points (origin, points, velocity and hits reset); 1: only one without any (config.py)
  int reseed_trusted_velocity_twists = 2;
  // ... when its new points' median lies farther than this from its old points' predicted
  // median (m)
  double reseed_reborn_min_offset_m = 2.0;
  // ... and only when predicted at least this far (camera z, m; config.py says why 15)
  double reseed_reborn_min_depth_m = 15.0;
  // rows before a re-birth whose row lies nearer than this (camera z, m), when there are at
  // least reborn_barrier_min_rows of them, stay out of the windows, the final smoothing and the
  // keyframe BA (0: none do): nothing but e_const links them to the new points
  double reborn_barrier_max_depth_m = 25.0;
  int reborn_barrier_min_rows = 3;
  // tracks of these classes (people) report rows without a box of their own only this near (m)
  std::vector<int> small_object_class_ids{24, 25};
  double small_object_report_max_depth_m = 35;
  double max_point_spread_m = 4.0;  // new points farther from the cluster median are dropped
  // a window moving a point farther than this fraction of its depth from where it joined the
  // cluster leaves it, and it is culled (tracks without a canonical frame)
  double window_max_point_move_depth_ratio = 0.5;
  double max_depth_m = 60;          // stereo points farther than this never join a cluster
  int max_points = 600;             // per cluster; the least often found are dropped first
  double min_found_ratio = 0.25;    // points matched in fewer of the frames predicting them
  int cull_after_visible = 5;       // ... are dropped once predicted this often
  int lm_iterations = 10;           // LM iterations per pass
  int window_frames = 8;            // sliding window of e_dyna + e_const + e_head (< 3: off)
  bool use_const = true;            // e_const in the window
  double const_sigma_translation = 0.05;  // m/frame, change of the translational twist
  double const_sigma_rotation = 0.005;    // rad/frame, change of the rotational twist
  double const_rotation_reference_step_m = 1.0;  // m/frame; slower: rotation sigma shrinks (0: off)
  double const_rotation_min_fraction = 0.1;      // of const_sigma_rotation, at rest
  double rest_sigma_translation = 0;  // m/frame; e_rest of camera-only tracks (0: off)
  int window_iterations = 5;        // Ceres iterations of the window
  double window_function_tolerance = 1e-3;  // the window stops at a smaller relative cost change (config.py)
  double recenter_distance_m = 0.5; // origin moved to the points' median beyond this (0: never)
  // ... unless the confirmed points' 10-90 % spread along an axis exceeds recenter_max_spread_m
  // (0: no limit) while the origin lies farther than recenter_spread_min_depth_m (m; config.py
  // says why these values)
  double recenter_max_spread_m = 6.0;
  double recenter_spread_min_depth_m = 25.0;
  // the median over the retired points too (those final_smoothing keeps; config.py says why)
  bool recenter_with_retired_points = true;
  // beyond recenter_spread_min_depth_m, the median (and the spread bound) over the confirmed
  // points seen in stereo when at least min_inliers of them are (config.py says why)
  bool recenter_on_stereo_points = true;
  // no re-centring while at most this fraction of the confirmed points were ever seen in
  // stereo: the others hold guessed depths, whose median is no centre (0: off; config.py)
  double recenter_min_stereo_fraction = 0.2;
  // a camera-only vehicle track's final rows turn at most (distance travelled) / this (m):
  // a car's turning radius (objects/track_turn.hpp; 0: off; config.py says why)
  double min_turn_radius_m = 5.0;
  // ... and one whose rows turned at least path_turn_min_excess_deg more than its path did,
  // while the chords over its first and last path_turn_chord_m of travel point within
  // path_turn_max_straight_deg of each other, takes one rotation on every row
  // (objects/track_turn.hpp, level_turn_off_its_path; excess 0: off; config.py says why)
  double path_turn_chord_m = 5.0;
  double path_turn_max_straight_deg = 15.0;
  double path_turn_min_excess_deg = 20.0;
  // once the sequence ends, every track's rows, all observations of its points and its LiDAR
  // terms in one problem (tracking/object_smoothing.cpp); the online poses are kept beside
  bool final_smoothing = true;
  int smoothing_iterations = 10;     // Ceres iterations of the final smoothing, per track
  int smoothing_frame_observations = 30;  // points join until each frame has this many (0: all)
  // m; a track without a canonical frame whose smoothing moves its reported rows by a median
  // of more than this from their online poses keeps its online poses (0: never; config.py
  // says why 1)
  double smoothing_max_median_move_m = 1.0;
  // non-holonomic prior in the window (optim/heading_cost.hpp), planar-link classes
  bool nonholonomic = true;
  double lateral_sigma_m = 0.02;     // m/frame across the travel axis
  // > 0: a vehicle without a travel axis yet gets the axis-free e_head (consecutive steps point
  // the same way in the object frame) where both steps are at least this long (m/frame); 0: off
  double axis_free_heading_min_step_m = 0;
  // > 0: its two displacements each span the fewest frames that make them this long (m)
  double axis_free_heading_min_chord_m = 0;
  double travel_min_path_m = 3.0;    // m travelled before the travel axis is trusted
  double travel_min_anisotropy = 10; // largest / second eigenvalue of the step moments
  double travel_min_straightness = 0.5;  // net displacement / path before the axis is trusted
  // extra keypoints inside object masks (tracking/object_keypoints.hpp)
  bool extra_keypoints = true;
  int extra_keypoints_max = 1000;     // per frame, over all object masks
  int extra_min_instance_keypoints = 40;  // fewer on a vehicle: a second pass on its mask (0: off)
  int extra_min_instance_area_px = 1000;  // ... of vehicles covering at least this many pixels
  int extra_keypoint_levels = 2;      // pyramid levels of the pass (<= the frame's)
  int extra_fast_threshold = 7;       // grey levels
  int extra_cell_px = 10;             // FAST retry grid cell (level px)
  double extra_min_spacing_px = 3;    // from every keypoint already in the frame
  double extra_min_depth_m = 1.5;     // SAD scan: closest depth searched
  double extra_max_sad_cost = 0.7;    // SAD scan: normalised cost accepted
  double extra_sad_uniqueness = 0.7;  // SAD scan: best / second-best minimum
  // left-right check of every object keypoint's stereo match (features::check_left_right)
  bool left_right_check = true;
  double left_right_tolerance_px = 2.0;  // level px between the match and its way back
  // object keypoints on the edge of an instance of these classes (people: thinner than the SAD
  // window) get their depth from its own pixels (features::depth_on_instance_pixels), with at
  // least this share of the window on them
  bool instance_pixel_stereo = true;
  std::vector<int> instance_pixel_class_ids{24, 25};
  double instance_pixel_min_fraction = 0.3;
  // vehicle keypoints at least pulled_nearer_min_depth_m away whose window covers another
  // vehicle lose their depth when their own vehicle's pixels alone match more than
  // pulled_nearer_max_px (level-0 px) farther: the nearer vehicle's texture made the match
  // (features::drop_matches_pulled_nearer; window share: instance_pixel_min_fraction)
  bool pulled_nearer_check = true;
  double pulled_nearer_min_depth_m = 35.0;
  double pulled_nearer_max_px = 0.5;
  // the stuff classes that count as another object beside a keypoint too (Cityscapes pole,
  // traffic light, traffic sign, vegetation: tree trunks and posts in front of parked cars)
  std::vector<int> pulled_nearer_occluder_class_ids{17, 19, 20, 21};
  // vehicle keypoints the right camera cannot see (left of a nearer vehicle's left edge, within
  // the two disparities' difference plus right_occlusion_margin_px, level-0 px) lose their
  // depth (features::drop_matches_occluded_in_right); an instance's disparity is the median of
  // at least right_occlusion_min_keypoints matched keypoints on it (off: measured on 41
  // sequences, it fixed queued cars' depth and lost others, docs/visual_objects.md)
  bool right_occlusion_check = false;
  double right_occlusion_margin_px = 0.5;
  int right_occlusion_min_keypoints = 5;
};

template <typename Visit>
void for_each_option(ObjectTrackingOptions& o, Visit&& visit) {
  visit("enabled", o.enabled, 0, 1);
  visit("object_class_ids", o.object_class_ids, 0, 65535);  // 16-bit panoptic class ids
  visit("planar_class_ids", o.planar_class_ids, 0, 65535);
  visit("road_class_id", o.road_class_id, -1, 65535);  // -1: no road cluster
  visit("road_max_depth_m", o.road_max_depth_m, 0.5, 10000.0);
  visit("road_lidar_points", o.road_lidar_points, 0, 1);
  visit("road_lidar_max_depth_m", o.road_lidar_max_depth_m, 0.5, 10000.0);
  visit("road_lidar_border_px", o.road_lidar_border_px, 0, 100);  // px: 100 is a 201 px window
  visit("road_plane_window_m", o.road_plane_window_m, 0.0, 1e9);
  visit("road_lidar_max_points", o.road_lidar_max_points, 0, 100000);  // 0: none kept
  visit("flow_radius_px", o.flow_radius_px, 0.0, 2000.0);  // px: 2000 spans any image
  visit("projection_radius_px", o.projection_radius_px, 0.0, 2000.0);
  visit("refine_radius_px", o.refine_radius_px, 0.0, 2000.0);
  visit("max_hamming", o.max_hamming, 0, 256);  // bits of a 256-bit descriptor
  visit("flow_max_hamming", o.flow_max_hamming, 0, 256);
  visit("min_new_cluster_points", o.min_new_cluster_points, 3, 100000);
  visit("min_new_planar_cluster_points", o.min_new_planar_cluster_points, 3, 100000);
  visit("ground_contact", o.ground_contact, 0, 1);
  visit("instance_border_px", o.instance_border_px, 0.0, 50.0);
  visit("min_contact_columns", o.min_contact_columns, 1, 100000);
  visit("min_contact_fraction", o.min_contact_fraction, 0.0, 1.0);
  visit("contact_depth_quantile", o.contact_depth_quantile, 0.0, 1.0);
  visit("min_contact_cluster_points", o.min_contact_cluster_points, 3, 100000);
  visit("contact_height_m", o.contact_height_m, 0.0, 2.0);
  visit("depth_fill_below_points", o.depth_fill_below_points, 0, 100000);
  visit("depth_fill_min_points", o.depth_fill_min_points, 1, 100000);
  visit("depth_fill_max_depth_m", o.depth_fill_max_depth_m, 0.5, 10000.0);
  visit("depth_fill_min_stereo_share", o.depth_fill_min_stereo_share, 0.0, 1.0);
  visit("min_shared_points", o.min_shared_points, 1, 100000);
  visit("min_mask_overlap", o.min_mask_overlap, 0.0, 1.0);
  visit("min_inliers", o.min_inliers, 3, 100000);  // 3 points fix a rigid motion
  visit("flow_observations_below_matches", o.flow_observations_below_matches, 0, 100000);
  visit("flow_observations_min_depth_m", o.flow_observations_min_depth_m, 0.0, 10000.0);
  visit("flow_observations_near_below_matches", o.flow_observations_near_below_matches, 0, 100000);
  visit("flow_observations_stereo", o.flow_observations_stereo, 0, 1);
  visit("flow_observations_lk_max_px", o.flow_observations_lk_max_px, 0.0, 1000.0);
  visit("max_step_m", o.max_step_m, 0.01, 1000.0);
  visit("max_misses", o.max_misses, 0, 100000);
  visit("reseed_after_misses", o.reseed_after_misses, 0, 100000);
  visit("untracked_report_max_depth_m", o.untracked_report_max_depth_m, 0.0, 10000.0);
  visit("untracked_contact_report_max_depth_m", o.untracked_contact_report_max_depth_m, 0.0, 10000.0);
  visit("untracked_reseed_max_jump_m", o.untracked_reseed_max_jump_m, 0.0, 10000.0);
  visit("reseed_trusted_velocity_twists", o.reseed_trusted_velocity_twists, 1, 100000);
  visit("reseed_reborn_min_offset_m", o.reseed_reborn_min_offset_m, 0.0, 10000.0);
  visit("reseed_reborn_min_depth_m", o.reseed_reborn_min_depth_m, 0.0, 10000.0);
  visit("reborn_barrier_max_depth_m", o.reborn_barrier_max_depth_m, 0.0, 10000.0);
  visit("reborn_barrier_min_rows", o.reborn_barrier_min_rows, 1, 100000);
  visit("small_object_class_ids", o.small_object_class_ids, 0, 65535);
  visit("small_object_report_max_depth_m", o.small_object_report_max_depth_m, 0.0, 10000.0);
  visit("max_point_spread_m", o.max_point_spread_m, 0.1, 1000.0);
  visit("window_max_point_move_depth_ratio", o.window_max_point_move_depth_ratio, 0.01, 1e6);
  visit("max_depth_m", o.max_depth_m, 0.5, 10000.0);
  visit("max_points", o.max_points, 3, 1000000);
  visit("min_found_ratio", o.min_found_ratio, 0.0, 1.0);
  visit("cull_after_visible", o.cull_after_visible, 1, 100000);
  visit("lm_iterations", o.lm_iterations, 1, 1000);
  visit("window_frames", o.window_frames, 0, 100);  // frames: 100 is a BA of seconds per frame
  visit("use_const", o.use_const, 0, 1);
  visit("const_sigma_translation", o.const_sigma_translation, 1e-6, 100.0);
  visit("const_sigma_rotation", o.const_sigma_rotation, 1e-6, 10.0);
  visit("const_rotation_reference_step_m", o.const_rotation_reference_step_m, 0.0, 100.0);
  visit("const_rotation_min_fraction", o.const_rotation_min_fraction, 1e-3, 1.0);
  visit("rest_sigma_translation", o.rest_sigma_translation, 0.0, 100.0);
  visit("window_iterations", o.window_iterations, 1, 1000);
  visit("window_function_tolerance", o.window_function_tolerance, 0.0, 1.0);  // of the cost
  visit("recenter_distance_m", o.recenter_distance_m, 0.0, 1000.0);
  visit("recenter_max_spread_m", o.recenter_max_spread_m, 0.0, 1000.0);
  visit("recenter_spread_min_depth_m", o.recenter_spread_min_depth_m, 0.0, 10000.0);
  visit("recenter_with_retired_points", o.recenter_with_retired_points, 0, 1);
  visit("recenter_on_stereo_points", o.recenter_on_stereo_points, 0, 1);
  visit("recenter_min_stereo_fraction", o.recenter_min_stereo_fraction, 0.0, 1.0);
  visit("min_turn_radius_m", o.min_turn_radius_m, 0.0, 1000.0);
  visit("path_turn_chord_m", o.path_turn_chord_m, 0.0, 1000.0);
  visit("path_turn_max_straight_deg", o.path_turn_max_straight_deg, 0.0, 180.0);
  visit("path_turn_min_excess_deg", o.path_turn_min_excess_deg, 0.0, 360.0);
  visit("final_smoothing", o.final_smoothing, 0, 1);
  visit("smoothing_iterations", o.smoothing_iterations, 1, 1000);
  visit("smoothing_frame_observations", o.smoothing_frame_observations, 0, 1000000);
  visit("smoothing_max_median_move_m", o.smoothing_max_median_move_m, 0.0, 1000.0);
  visit("nonholonomic", o.nonholonomic, 0, 1);
  visit("lateral_sigma_m", o.lateral_sigma_m, 1e-4, 100.0);
  visit("axis_free_heading_min_step_m", o.axis_free_heading_min_step_m, 0.0, 100.0);
  visit("axis_free_heading_min_chord_m", o.axis_free_heading_min_chord_m, 0.0, 1000.0);
  visit("travel_min_path_m", o.travel_min_path_m, 0.0, 10000.0);
  visit("travel_min_anisotropy", o.travel_min_anisotropy, 1.0, 1e6);
  visit("travel_min_straightness", o.travel_min_straightness, 0.0, 1.0);
  visit("extra_keypoints", o.extra_keypoints, 0, 1);
  visit("extra_keypoints_max", o.extra_keypoints_max, 0, 100000);
  visit("extra_min_instance_keypoints", o.extra_min_instance_keypoints, 0, 100000);
  visit("extra_min_instance_area_px", o.extra_min_instance_area_px, 0, 100000000);
  visit("extra_keypoint_levels", o.extra_keypoint_levels, 1, 32);
  visit("extra_fast_threshold", o.extra_fast_threshold, 1, 254);  // grey levels of 8 bits
  visit("extra_cell_px", o.extra_cell_px, 8, 4096);  // as OrbOptions::cell_size
  visit("extra_min_spacing_px", o.extra_min_spacing_px, 0.0, 100.0);
  visit("extra_min_depth_m", o.extra_min_depth_m, 0.1, 1000.0);
  visit("extra_max_sad_cost", o.extra_max_sad_cost, 1e-3, 10.0);
  visit("extra_sad_uniqueness", o.extra_sad_uniqueness, 0.01, 1.0);
  visit("left_right_check", o.left_right_check, 0, 1);
  visit("left_right_tolerance_px", o.left_right_tolerance_px, 0.0, 100.0);
  visit("instance_pixel_stereo", o.instance_pixel_stereo, 0, 1);
  visit("instance_pixel_class_ids", o.instance_pixel_class_ids, 0, 65535);
  visit("instance_pixel_min_fraction", o.instance_pixel_min_fraction, 0.0, 1.0);
  visit("pulled_nearer_check", o.pulled_nearer_check, 0, 1);
  visit("pulled_nearer_min_depth_m", o.pulled_nearer_min_depth_m, 0.0, 10000.0);
  visit("pulled_nearer_max_px", o.pulled_nearer_max_px, 0.0, 1000.0);
  visit("pulled_nearer_occluder_class_ids", o.pulled_nearer_occluder_class_ids, 0, 65535);
  visit("right_occlusion_check", o.right_occlusion_check, 0, 1);
  visit("right_occlusion_margin_px", o.right_occlusion_margin_px, 0.0, 1000.0);
  visit("right_occlusion_min_keypoints", o.right_occlusion_min_keypoints, 1, 1000000);
}

}  // namespace twistslam::tracking
