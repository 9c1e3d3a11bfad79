// The canonical object frame (paper sec. "Injecting LiDAR scans"): the first box associated
// with a cluster sets its object frame (the box frame); the frame then turns by pi if the car
// drives backwards in it (a LiDAR box's heading is known mod pi), and is re-anchored to the
// weighted mean offset of all its boxes (objects/box_offset.hpp): the first box alone leaves
// its own noise (the simulator's oracle: ~0.1 m, ~2 deg) in every pose of the track. A car
// that does not move faces the way most of its boxes do (detectors that know the heading; a
// box known mod pi votes with the heading of parked traffic on its side of the road).
#include <algorithm>
#include <cmath>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "objects/association.hpp"
#include "objects/box_offset.hpp"
#include "objects/box_travel.hpp"
#include "objects/track_turn.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
using detail::transform;

namespace {
// a line through fewer boxes is no direction: two boxes are the first-to-last difference
constexpr int kHeadingMinBoxes = 3;
}  // namespace

void ObjectTracker::level_cluster_turn(int c) {
  // a car turns a few deg/frame at most (10 Hz; the simulator's sharpest onset: 3.3): a
  // cluster's twist from a handful of far points spun urban s0's oncoming car 11 by ~11
  // deg/frame from its birth at 47 m, and the box that made it canonical left that history in
  // its earlier rows, which the window's fixed first row and e_const then held against the
  // boxes (yaw 18-33 deg off for 10 frames with range-scaled e_det sigmas)
  objects::ObjectTrack& track = tracks_[c];
  if (!objects::level_made_up_turn(&track, lidar_options_.cluster_turn_max_deg_per_frame)) return;
  clusters_[c].velocity = track.frames[track.frames.size() - 2].xi;  // its prediction too
}

void ObjectTracker::make_canonical(int c, const Mat4& T_w_box) {
  objects::ObjectTrack& track = tracks_[c];
  // T_w_o' = T_w_o T_o_o' for every frame: a change of the object frame only, the twists of
  // eq. 2 (left-multiplied in w) are unchanged; points and the travel axis re-expressed
  const Mat4 T_o_new = geometry::se3_inverse(track.last().T_w_o) * T_w_box;
  const Mat4 T_new_o = geometry::se3_inverse(T_o_new);
  for (objects::TrackFrame& row : track.frames) row.T_w_o = row.T_w_o * T_o_new;
  for (objects::TrackFrame& row : track.backcast) row.T_w_o = row.T_w_o * T_o_new;
  for (auto* points : {&clusters_[c].points, &clusters_[c].retired})
    for (objects::ObjectPoint& p : *points)
      p.X_o = transform(T_new_o, p.X_o), p.X_o_placed = transform(T_new_o, p.X_o_placed);
  track.travel.rotate(T_o_new.topLeftCorner<3, 3>());
  // the front profile's views are signed along x: a turn by pi flips them, a quarter turn
  // leaves them about another axis
  const double x_turn = T_o_new(0, 0);  // cos of the angle between the old and new x axes
  if (std::abs(x_turn) < std::cos(M_PI / 4))
    track.front_profile_m.clear();
  else if (x_turn < 0)
    for (double& d : track.front_profile_m) d = -d;
  track.canonical = true;
}

void ObjectTracker::check_heading_from_motion(int c) {
  objects::ObjectTrack& track = tracks_[c];
  if (!track.last().has_detection() || !(lidar_options_.heading_from_motion_m > 0)) return;
  // the motion of the box centres, not of the tracked poses: boxes do not drift, while a far
  // cluster's visual twist can run the wrong way for frames (an oncoming car at 50 m turned a
  // correct oracle box around, urban seed 1); a line through all of them, not the first box
  // to the last: a wrong first box (2 m off) decided the direction alone
  std::vector<objects::BoxCentre> centres;
  for (const objects::TrackFrame& row : track.frames)
    if (row.frame >= track.canonical_frame && row.has_detection())
      centres.push_back({row.frame, row.T_w_o_detected.topRightCorner<3, 1>()});
  const objects::BoxTravel travel = objects::box_travel(centres);
  if (!travel.valid || travel.inliers < kHeadingMinBoxes ||
      travel.distance_m < lidar_options_.heading_from_motion_m ||
      travel.distance_m < lidar_options_.heading_motion_min_sigmas * travel.distance_sigma_m)
    return;
  // a car drives along its length: box centres that travel across the frame's x axis are the
  // boxes' own errors, not a drive (urban s11's car 22, stopped across the camera's road at
  // 44-48 m: its first three oracle boxes 3 m short and facing backwards made a 3 m "travel"
  // sideways, whose sign against the axis turned the frame around for good)
  const Vec3 axis_w = track.last().T_w_o.block<3, 1>(0, 0);
  const double max_angle_rad = lidar_options_.heading_motion_max_angle_deg * M_PI / 180.0;
  if (std::abs(axis_w.dot(travel.velocity_w)) < std::cos(max_angle_rad) * travel.velocity_w.norm())
    return;
  track.heading_from_motion = true;
  // a car drives forward: its box frame faced backwards (a LiDAR box's heading is known mod pi)
  if (axis_w.dot(travel.velocity_w) < 0) turn_canonical_around(c);
}

void ObjectTracker::check_heading_from_votes(int c) {
  objects::ObjectTrack& track = tracks_[c];
  if (!lidar_options_.heading_from_votes) return;
  // the first box set the frame: a box whose heading is off by pi (the simulator's oracle: 2 %
  // of its boxes; a learned detector's front / back confusion) turned a parked car's whole
  // track around, and a car that never moves has no motion to turn it back (urban seed 4's
  // car 20: yaw 180 deg in every frame). Each box votes with its own heading in its frame.
  // One box, one vote: scores are not comparable across detectors (PointRCNN's may be negative).
  // A box without a heading of its own votes with its road side's (road_side_heading).
  int agree = 0, against = 0;
  for (const objects::TrackFrame& row : track.frames) {
    if (!row.has_detection()) continue;
    const Vec3& heading_w =
        row.detected_heading_w.isZero() ? row.road_side_heading_w : row.detected_heading_w;
    if (heading_w.isZero()) continue;
    ++(heading_w.dot(row.T_w_o.block<3, 1>(0, 0)) >= 0 ? agree : against);
  }
  // its own returns' height profile (object_front_profile.cpp): once its views' mean is clear,
  // each view votes like a box that told the front. Classical urban s13's car 21, stopped
  // across the road: 16 views against one box whose own profile put the front at the far end
  const int front = front_from_profile_views(track);
  if (front != 0) (front > 0 ? agree : against) += static_cast<int>(track.front_profile_m.size());
  if (agree + against >= kHeadingMinBoxes && against > agree) turn_canonical_around(c);
}

Vec3 road_side_heading(const Mat4& T_w_c, const Mat4& T_w_box, const ObjectLidarOptions& o) {
  if (o.road_side_heading == 0) return Vec3::Zero();
  // the camera's travel and right (x right, z forward) and the box's length axis, in w
  const Vec3 forward_w = T_w_c.block<3, 1>(0, 2), right_w = T_w_c.block<3, 1>(0, 0);
  const Vec3 axis_w = T_w_box.block<3, 1>(0, 0);
  const Vec3 from_camera_w = T_w_box.topRightCorner<3, 1>() - T_w_c.topRightCorner<3, 1>();
  const double lateral = from_camera_w.dot(right_w);
  const double along = axis_w.dot(forward_w);
  if (std::abs(lateral) < o.road_side_min_lateral_m || std::abs(lateral) > o.road_side_max_lateral_m ||
      std::abs(along) < std::cos(o.road_side_max_angle_deg * M_PI / 180.0))
    return Vec3::Zero();
  // right-hand traffic: beside the camera on its right, the traffic (and a car parked at
  // that curb) goes the camera's way; on its left, the other way
  const double facing = (lateral > 0 ? 1.0 : -1.0) * static_cast<double>(o.road_side_heading);
  return along * facing > 0 ? axis_w : Vec3(-axis_w);
}

void ObjectTracker::turn_canonical_around(int c) {
  objects::ObjectTrack& track = tracks_[c];
  // the frame turns by pi about its y axis, and the boxes aligned with it turn too
  make_canonical(c, objects::turned_around(track.last().T_w_o));
  for (objects::TrackFrame& row : track.frames)
    if (row.has_detection()) row.T_w_o_detected = objects::turned_around(row.T_w_o_detected);
}

void ObjectTracker::refine_canonical(int c) {
  objects::ObjectTrack& track = tracks_[c];
  if (!lidar_options_.refine_canonical || !track.canonical) return;
  std::vector<objects::BoxOffsetSample> samples;
  for (const objects::TrackFrame& row : track.frames) {
    if (!row.has_detection()) continue;
    // a box centre's noise grows with its range (sparser returns); nearer than the floor,
    // truncation and partial views, not range, limit it
    const double sigma_range = std::max(row.range, lidar_options_.refine_min_range_m);
    samples.push_back({geometry::se3_inverse(row.T_w_o) * row.T_w_o_detected,
                       1.0 / (sigma_range * sigma_range)});
  }
  if (samples.size() < static_cast<size_t>(lidar_options_.refine_min_boxes)) return;
  const objects::BoxOffset offset = objects::mean_box_offset(samples);
  // a frame refined by boxes that disagree among themselves would chase a track whose poses
  // drift (a far cluster's wrong visual twist): most boxes must agree on the offset
  if (!offset.valid || offset.inliers < lidar_options_.refine_min_agreement * static_cast<double>(samples.size()))
    return;
  const double shift_m = offset.T_o_box.topRightCorner<3, 1>().norm();
  const double turn_rad = geometry::so3_log(offset.T_o_box.topLeftCorner<3, 3>()).norm();
  if (shift_m < lidar_options_.refine_min_shift_m && turn_rad < lidar_options_.refine_min_turn_rad) return;
  make_canonical(c, track.last().T_w_o * offset.T_o_box);
}

}  // namespace twistslam::tracking

