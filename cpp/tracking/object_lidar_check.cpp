// A camera-only vehicle track the LiDAR contradicts is not reported (not in the paper).
// Without a 3D box, a car's position is its cluster's stereo depth, and far cars' stereo fails
// in one direction: their corners lie on a nearer occluder's edge and take part of its
// disparity. Urban seed 5's parked car 24, at 57 m among nearer occluders (a building, a tree
// trunk, a parked car), was tracked 4-5 m short for 23 frames (its stereo matches 0.65 px high),
// a ghost; the returns on its own mask around its points put them 6 % (2.8 m) farther, row
// after row. Each checked row adds its median ratio and offset to the track's; the track's
// medians decide, and its rows without a box of their own (a box places the track) are
// hidden, earlier ones too. Measured on the camera-only
// vehicle tracks of eight simulated sequences (default row, urban s0, s2, s5, s8, s9, s11,
// crowded s1, s6; 6129 checked rows): three tracks of 5+ checked rows had a median ratio above
// 1.02: 1.028 (0.9 m, a car it follows), 1.056 (2.2 m, urban s9's parked car 14, drifting
// 1.3-3.7 m off) and 1.060 (urban s5's ghost). The far side (points beyond the returns) has its
// own, wider bounds (lidar_check_max_far_ratio).
#include <algorithm>
#include <cmath>
#include <vector>

#include "tracking/instance_pixels.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
using detail::median_value;
using detail::transform;

void ObjectTracker::hide_lidar_contradicted_tracks(const Frame& frame) {
  const ObjectLidarOptions& o = lidar_options_;
  const bool either_side = o.lidar_check_max_ratio > 0 || o.lidar_check_max_far_ratio > 0;
  if (!scan_ || instances_.empty() || !either_side) return;
  for (size_t c = 0; c < tracks_.size(); ++c) {
    objects::ObjectTrack& track = tracks_[c];
    const objects::ObjectCluster& cluster = clusters_[c];
    if (!track.alive() || track.canonical || track.frames.empty() || cluster.instance <= 0 ||
        track.link != geometry::LinkType::kPlanar)
      continue;
    objects::TrackFrame& row = track.last();
    if (row.frame != frame.index || !row.reported || row.has_detection()) continue;
    const std::vector<double>* returns = mask_lidar_depths(cluster.instance);
    if (static_cast<int>(returns->size()) < o.lidar_check_min_returns) continue;
    // each of the cluster's points on the mask against the returns around it (the surface the
    // LiDAR sees there): a local comparison, since a queued car shows its rear edge and its
    // roof, whose returns run along its length
    const Mat4 T_c_o = frame.T_c_w * row.T_w_o;
    std::vector<double> nearer_by, ratios;
    for (const objects::ObjectPoint& p : cluster.points) {
      const Vec3 X_c = transform(T_c_o, p.X_o);
      if (X_c.z() <= 0.1) continue;
      const Vec2 uv = camera_.project(X_c);
      if (!camera_.in_image(uv) || pixel_value(instances_, uv) != cluster.instance) continue;
      const double lidar_depth = instance_lidar_depth_near(cluster.instance, uv);
      if (!std::isfinite(lidar_depth)) continue;
      nearer_by.push_back(lidar_depth - X_c.z());
      ratios.push_back(lidar_depth / X_c.z());
    }
    if (static_cast<int>(nearer_by.size()) < o.lidar_check_min_points) continue;
    track.lidar_depth_ratios.push_back(median_value(ratios));
    track.lidar_depth_offsets_m.push_back(median_value(nearer_by));
    if (lidar_contradicts(track)) hide_lidar_contradicted_rows(&track);
  }
}

bool ObjectTracker::lidar_contradicts(const objects::ObjectTrack& track) const {
  const ObjectLidarOptions& o = lidar_options_;
  const bool near_side = o.lidar_check_max_ratio > 0, far_side = o.lidar_check_max_far_ratio > 0;
  if (!(near_side || far_side) ||
      static_cast<int>(track.lidar_depth_ratios.size()) < o.lidar_check_min_rows)
    return false;
  // a track with boxes is placed by them (e_det, the pose prior), not by its points' depth:
  // crowded s4's queued car 16 (classical detector), its track within 0.2 m of it, held points
  // of the car ahead that read 40 % nearer than its own mask's returns
  if (std::any_of(track.frames.begin(), track.frames.end(),
                  [](const objects::TrackFrame& r) { return r.has_detection(); }))
    return false;
  // the track's verdict, not the row's: a car's points on its rear edge and the returns on its
  // roof differ by metres in single rows of cars the track follows well (urban s0, s2, s5, s8,
  // s9, s11, crowded s1, s6: at 2 m and 4 %, 31 such rows hidden for 22 rows off every object)
  const double ratio = median_value(track.lidar_depth_ratios);
  const double offset_m = median_value(track.lidar_depth_offsets_m);
  if (near_side && ratio - 1.0 > o.lidar_check_max_ratio && offset_m > o.lidar_check_min_offset_m)
    return true;
  // the far side: a track whose points lie beyond its own mask's returns moves along the line
  // of sight, which its projections barely show (urban s8's track 36, born on a parked car at
  // 45 m, drove away at 1.1 m/frame: its points 4-8 m beyond the returns, median ratio 0.88)
  return far_side && 1.0 - ratio > o.lidar_check_max_far_ratio &&
         -offset_m > o.lidar_check_min_far_offset_m;
}

void ObjectTracker::hide_lidar_contradicted_rows(objects::ObjectTrack* track) {
  for (objects::TrackFrame& r : track->frames)
    if (r.reported && !r.has_detection()) r.reported = false, r.lidar_contradicted = true;
}

// Online, the medians of a track's first rows decide for them; at the end, all its rows do.
// Urban s8's car 32 (unseen seed): its track's first rows were hidden online, 8 of its 32
// frames (coverage 1.00 -> 0.75), while the medians over all its rows stay below the bounds.
void ObjectTracker::retest_lidar_contradiction() {
  for (objects::ObjectTrack& track : tracks_) {
    if (lidar_contradicts(track)) {
      hide_lidar_contradicted_rows(&track);
      continue;
    }
    for (objects::TrackFrame& r : track.frames)
      if (r.lidar_contradicted) r.reported = true, r.lidar_contradicted = false;
  }
}

}  // namespace twistslam::tracking
