// A canonical track whose box the LiDAR sees through is not where its car is: not reported in
// that frame (objects/box_free_space.hpp). Oracle urban seed 4: a second cluster on a parked
// car took one of its boxes, then tracked points 3-4 m beyond it for 45 frames, reported as a
// ghost; the car's own track had every other box. Only frames without a box of its own: a box
// this frame places the track on returns.
#include "geometry/se3.hpp"
#include "objects/box_free_space.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {

void ObjectTracker::hide_see_through_tracks(const Frame& frame) {
  if (!scan_ || lidar_options_.see_through_min_rays <= 0) return;
  for (objects::ObjectTrack& track : tracks_) {
    if (!track.alive() || !track.canonical || track.frames.empty() || !(track.size.minCoeff() > 0))
      continue;
    objects::TrackFrame& row = track.last();
    if (row.frame != frame.index || !row.reported || row.has_detection()) continue;
    // the rays start at the camera: the LiDAR's origin is ~0.3 m away (KITTI), which the
    // shrunk box absorbs
    const objects::BoxRayCounts counts = objects::count_box_rays(
        *scan_, frame.T_c_w * row.T_w_o, track.size, Vec3::Zero(), lidar_options_.see_through_shrink_m);
    if (counts.through >= lidar_options_.see_through_min_rays &&
        counts.through >= lidar_options_.see_through_ratio * counts.inside)
      row.reported = false;
  }
}

}  // namespace twistslam::tracking
