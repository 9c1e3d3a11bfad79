#pragma once
// Local mapping: when a tracked frame becomes a keyframe (TwistSLAM's temporal and spatial
// criteria, ORB-SLAM2's close-point rule), what its insertion adds (observations, new stereo
// points), culling of recent points, the local bundle adjustment (static half of paper
// eq. 9) and the bound on the map's size. Map segments start here too: a segment's first
// keyframe holds the gauge of every BA in it.
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "tracking/frame.hpp"
#include "tracking/level_weights.hpp"
#include "tracking/object_bundle_terms.hpp"
#include "tracking/options.hpp"

namespace twistslam::tracking {

struct KeyframeInsertion {
  int keyframe_id = -1;
  int new_points = 0;            // stereo matches of the frame that became map points
  bool bundle_adjusted = false;  // false: the keyframe was alone in its window (a segment start)
  double ba_ms = 0;              // wall time of the local BA
};

class LocalMapper {
 public:
  LocalMapper(const geometry::StereoCamera& camera, const SlamOptions& options, LevelWeights weights);

  // Enough usable stereo points (tracking.min_init_points) to start a map on this frame.
  bool can_start_segment(const Frame& frame) const;
  // A new map segment (the first frame, or a restart after tracking loss) whose first
  // keyframe is this frame (its matches must be cleared).
  KeyframeInsertion start_segment(Frame& frame, map::Map& map);

  // The keyframe decision for a tracked frame; reference_keyframe: the keyframe sharing most
  // of its points (-1: none, no keyframe).
  bool need_keyframe(const Frame& frame, const map::Map& map, int reference_keyframe) const;
  // Adds frame as a keyframe of the current segment: its inlier matches become observations
  // (outliers are unmatched), its other stereo keypoints new points (frame.point_ids gets
  // them, so the next frame tracks them); then culling, local BA (with the moving objects'
  // terms when `objects` is given) and the map bound.
  KeyframeInsertion insert_keyframe(Frame& frame, map::Map& map, ObjectBundleTerms* objects = nullptr);

  void reset();

 private:
  int create_stereo_points(Frame& frame, map::Map& map, int keyframe_id);
  void cull_recent_points(map::Map& map, int keyframe_id);
  void bound_map_size(map::Map& map) const;

  geometry::StereoCamera camera_;
  TrackingOptions tracking_options_;
  KeyframeOptions keyframe_options_;
  LocalBAOptions ba_options_;
  MapOptions map_options_;
  LevelWeights weights_;

  int segment_ = -1;
  int segment_first_keyframe_ = -1;  // holds the segment's gauge in every local BA
  int last_keyframe_frame_ = -1;     // frame index of the newest keyframe (temporal criterion)
  std::vector<int> recent_points_;   // created by the last few keyframes, still on probation
};

}  // namespace twistslam::tracking
