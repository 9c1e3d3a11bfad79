#pragma once
// Options of the stereo SLAM system. The defaults here and the ranges of for_each_option
// (options.cpp) are what the core applies, whether it is called from twistslam.Config or
// directly; python/twistslam/config.py explains each default, and tests/python/test_config.py
// checks that its defaults equal these key for key.
#include <vector>

#include "features/orb.hpp"
#include "features/stereo.hpp"
#include "features/stereo_option_ranges.hpp"
#include "tracking/lidar_keypoint_depth.hpp"
#include "tracking/object_lidar_options.hpp"
#include "tracking/object_tracking_options.hpp"

namespace twistslam::tracking {

struct TrackingOptions {
  int min_inliers = 30;                  // below: the frame is lost
  int min_init_points = 100;             // stereo points needed to start (or restart) a map
  double search_radius_px = 15;          // motion-model projection search (level-0 px)
  double local_map_search_radius_px = 4; // local-map projection search (level-0 px)
  // the frame after a map start (no velocity): predicted by descriptor matches + PnP RANSAC
  bool descriptor_prediction = true;
  int max_hamming = 40;                  // accepted descriptor distance (bits)
  double ratio_test = 0.7;               // best / second-best distance within a cell
  int pose_rounds = 4;                   // outlier-rejection rounds of the pose optimisation
  double chi2_stereo = 7.815;            // 95 % of chi2 with 3 dof
  double chi2_mono = 5.991;              // 95 % of chi2 with 2 dof
  double close_depth_baselines = 40;     // keypoints nearer than this many baselines are "close" (keyframe rule)
  std::vector<int> dynamic_class_ids;    // classes whose keypoints never track the camera (eq. 3)
};

struct KeyframeOptions {
  int max_frames_between = 2;        // temporal keyframe (TwistSLAM)
  // ... only once the camera has moved this far from the reference keyframe (m) or turned this
  // much (deg): a stopped camera's keyframes repeat one view, give the BA nothing, and every
  // one adds an observation to each point (per-keyframe cost grows with the stop's length)
  double temporal_min_translation_m = 0.05;
  double temporal_min_rotation_deg = 0.5;
  double min_tracked_ratio = 0.75;   // spatial: tracked points vs the reference keyframe
  int min_close_tracked = 100;       // few close points tracked ...
  int min_new_close = 70;            // ... and this many new close ones could be added
};

struct LocalBAOptions {
  int window = 10;           // keyframes optimised
  int max_fixed = 20;        // covisible keyframes held fixed around the window
  int iterations_first = 3;  // before removing outlier observations
  int iterations_second = 4;
  double huber_stereo = 2.796;  // sqrt(7.815)
  double huber_mono = 2.448;    // sqrt(5.991)
  int num_threads = 1;  // 1: bit-for-bit reproducible runs (config.py has the figures)
  // the solve runs in a thread of its own beside the next frame's front end (config.py)
  bool asynchronous = true;
  // frames tracked against the map before the asynchronous BA is applied to it (config.py)
  int apply_delay_frames = 0;
  // e_dyna: the tracked objects' keypoints, poses and points join the BA (config.py)
  bool dynamic_objects = false;
  int dynamic_points_per_object = 20;         // the most often found points of each object
  double dynamic_link_sigma_translation = 0.1; // m, out-of-link motion between keyframes
  double dynamic_link_sigma_rotation = 0.02;   // rad
  // e_const between the objects' keyframe poses (visual_objects' sigmas and use_const)
  bool dynamic_const = true;
};

struct MapOptions {
  double min_found_ratio = 0.25;  // culled when matched in fewer of the frames that saw it
  int cull_after_keyframes = 2;   // a new point is judged after this many keyframes
  int max_points = 200000;        // memory bound: oldest points dropped beyond it
};

// The SLAM front end extracts more features than the extractor's generic default (2000):
// with 3000 per image more matches average out the per-frame pose noise (rotation RPE ~20 %
// lower on the simulator; python/twistslam/config.py has the figures).
inline features::OrbOptions slam_orb_options() {
  features::OrbOptions o;
  o.num_features = 3000;
  return o;
}

struct SlamOptions {
  features::OrbOptions orb = slam_orb_options();
  features::StereoOptions stereo;
  TrackingOptions tracking;
  KeyframeOptions keyframes;
  LocalBAOptions local_ba;
  MapOptions map;
  LidarOptions lidar;  // keypoint depth from a frame's scan (tracking/lidar_keypoint_depth.hpp)
  ObjectTrackingOptions visual_objects;  // object clusters (tracking/object_tracker.hpp)
  ObjectLidarOptions lidar_objects;      // their LiDAR fusion (tracking/object_lidar_options.hpp)
};

// Each section's fields with their valid ranges (inclusive, the field's unit), visited as
// visit("key", field, lo, hi); see options/option_range.hpp. Upper bounds lie far beyond any
// useful value: they refuse overflowing input (a radius of 1e30 px, 3e9 features) by name.
template <typename Visit>
void for_each_option(TrackingOptions& o, Visit&& visit) {
  // inliers / points: more than extract_orb's 1e5 keypoints can never be met
  visit("min_inliers", o.min_inliers, 1, 100000);
  visit("min_init_points", o.min_init_points, 1, 100000);
  // level-0 px: 2000 px searches the whole of any camera image already (the motion model
  // widens it up to 4x); the bound keeps the grid's cell arithmetic inside int
  visit("search_radius_px", o.search_radius_px, 0.0, 2000.0);
  visit("local_map_search_radius_px", o.local_map_search_radius_px, 0.0, 2000.0);
  visit("descriptor_prediction", o.descriptor_prediction, 0, 1);
  visit("max_hamming", o.max_hamming, 0, 256);  // bits of a 256-bit descriptor
  visit("ratio_test", o.ratio_test, 0.0, 1.0);
  // rounds of a full pose solve: ORB-SLAM2 needs 4, 100 re-classify far past convergence
  visit("pose_rounds", o.pose_rounds, 1, 100);
  // chi-square gates: 1e4 is a 100-sigma gate, i.e. no gating
  visit("chi2_stereo", o.chi2_stereo, 0.0, 10000.0);
  visit("chi2_mono", o.chi2_mono, 0.0, 10000.0);
  // baselines: 1e4 baselines (5 km on KITTI) makes every point "close"
  visit("close_depth_baselines", o.close_depth_baselines, 0.0, 10000.0);
  // class ids of a 16-bit panoptic label image
  visit("dynamic_class_ids", o.dynamic_class_ids, 0, 65535);
}

template <typename Visit>
void for_each_option(KeyframeOptions& o, Visit&& visit) {
  visit("max_frames_between", o.max_frames_between, 1, 100000);  // frames: ~3 h at 10 Hz
  // 0: every temporal keyframe, moving or not; 1 km / 180 deg: only the spatial rules
  visit("temporal_min_translation_m", o.temporal_min_translation_m, 0.0, 1000.0);
  visit("temporal_min_rotation_deg", o.temporal_min_rotation_deg, 0.0, 180.0);
  visit("min_tracked_ratio", o.min_tracked_ratio, 0.0, 1.0);
  visit("min_close_tracked", o.min_close_tracked, 0, 100000);  // points: extract_orb's limit
  visit("min_new_close", o.min_new_close, 0, 100000);
}

template <typename Visit>
void for_each_option(LocalBAOptions& o, Visit&& visit) {
  // keyframes: a window of 500 is a BA of minutes per keyframe, far past a local BA
  visit("window", o.window, 1, 500);
  visit("max_fixed", o.max_fixed, 0, 500);
  // Ceres iterations: LM converges in tens; 1000 is "until converged"
  visit("iterations_first", o.iterations_first, 0, 1000);
  visit("iterations_second", o.iterations_second, 0, 1000);
  // px: a Huber kink of 0 is undefined (Ceres divides by it); 1000 px is larger than the
  // image, i.e. a plain least-squares cost
  visit("huber_stereo", o.huber_stereo, 0.01, 1000.0);
  visit("huber_mono", o.huber_mono, 0.01, 1000.0);
  visit("num_threads", o.num_threads, 1, 256);  // threads: more than any CPU here
  visit("asynchronous", o.asynchronous, 0, 1);
  // frames: one BA pending at a time; a keyframe insertion always applies it first
  visit("apply_delay_frames", o.apply_delay_frames, 0, 1);
  visit("dynamic_objects", o.dynamic_objects, 0, 1);
  visit("dynamic_points_per_object", o.dynamic_points_per_object, 0, 100000);  // a cluster's max_points bound
  visit("dynamic_link_sigma_translation", o.dynamic_link_sigma_translation, 1e-6, 100.0);  // m
  visit("dynamic_link_sigma_rotation", o.dynamic_link_sigma_rotation, 1e-6, 10.0);  // rad
  visit("dynamic_const", o.dynamic_const, 0, 1);
}

template <typename Visit>
void for_each_option(MapOptions& o, Visit&& visit) {
  visit("min_found_ratio", o.min_found_ratio, 0.0, 1.0);
  visit("cull_after_keyframes", o.cull_after_keyframes, 0, 100000);  // keyframes
  // points: 1e8 points are ~50 GB of descriptors and observations
  visit("max_points", o.max_points, 1, 100000000);
}

// Every section of SlamOptions under its name in twistslam.Config, as visit(name, section).
template <typename VisitSection>
void for_each_section(SlamOptions& o, VisitSection&& visit) {
  visit("orb", o.orb);
  visit("stereo", o.stereo);
  visit("tracking", o.tracking);
  visit("keyframes", o.keyframes);
  visit("local_ba", o.local_ba);
  visit("map", o.map);
  visit("lidar", o.lidar);
  visit("visual_objects", o.visual_objects);
  visit("lidar_objects", o.lidar_objects);
}

// Throws std::invalid_argument naming the option ("tracking.search_radius_px = inf is out of
// range [0, 2000]") for any value outside its range, and for min_depth >= max_depth or
// min_fast_threshold > fast_threshold.
void check_options(const SlamOptions& options);

}  // namespace twistslam::tracking
