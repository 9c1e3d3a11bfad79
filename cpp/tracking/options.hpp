#pragma once
// Options of the stereo SLAM system. The Python Config (python/twistslam/config.py) is the
// single place where defaults are explained; these defaults mirror it for C++-only use.
#include <vector>

#include "features/orb.hpp"
#include "features/stereo.hpp"

namespace twistslam::tracking {

struct TrackingOptions {
  int min_inliers = 30;                  // below: the frame is lost
  int min_init_points = 100;             // stereo points needed to start (or restart) a map
  double search_radius_px = 15;          // motion-model projection search (level-0 px)
  double local_map_search_radius_px = 4; // local-map projection search (level-0 px)
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
  int num_threads = 2;
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
};

}  // namespace twistslam::tracking
