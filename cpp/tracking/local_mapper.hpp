#pragma once
// Local mapping: when a tracked frame becomes a keyframe (TwistSLAM's temporal and spatial
// criteria, ORB-SLAM2's close-point rule), what its insertion adds (observations, new stereo
// points), culling of recent points, the local bundle adjustment (static half of paper
// eq. 9) and the bound on the map's size. Map segments start here too: a segment's first
// keyframe holds the gauge of every BA in it.
//
// With local_ba.asynchronous the BA's solve runs in a thread of its own while the caller goes
// on (the next frame's features and stereo); finish_bundle_adjustment applies it. The caller
// decides when, so runs stay reproducible: the same frames see the same refined map as
// with the synchronous BA.
#include <exception>
#include <memory>
#include <thread>
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
  bool ba_pending = false;       // the BA is solving in its thread (finish_bundle_adjustment)
  double ba_ms = 0;              // wall time of the local BA (synchronous)
};

// What finish_bundle_adjustment applied.
struct FinishedBundleAdjustment {
  bool applied = false;   // false: no BA was pending
  int keyframe_id = -1;   // the keyframe whose insertion started it
  int frame_index = -1;
  double solve_ms = 0;    // the solve's wall time in its thread
  double wait_ms = 0;     // how long the caller waited for it
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
  // With local_ba.asynchronous the BA is only started (insertion.ba_pending): the map and the
  // objects must not change until finish_bundle_adjustment, which must precede any use of them.
  KeyframeInsertion insert_keyframe(Frame& frame, map::Map& map, ObjectBundleTerms* objects = nullptr);
  // Waits for the pending BA, if any, and applies it (then the map bound); rethrows what its
  // thread threw.
  FinishedBundleAdjustment finish_bundle_adjustment(map::Map& map);
  bool bundle_adjustment_pending() const { return pending_ != nullptr; }

  // Drops a pending BA unapplied.
  void reset();
  ~LocalMapper();
  LocalMapper(const LocalMapper&) = delete;
  LocalMapper& operator=(const LocalMapper&) = delete;

 private:
  int create_stereo_points(Frame& frame, map::Map& map, int keyframe_id);
  void cull_recent_points(map::Map& map, int keyframe_id);
  void bound_map_size(map::Map& map) const;
  void join_worker();

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

  struct PendingBA;  // the job, its thread and what the thread threw
  std::unique_ptr<PendingBA> pending_;
};

}  // namespace twistslam::tracking
