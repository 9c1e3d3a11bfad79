#pragma once
// The object track: one state for every source that observes an object (3D detections now;
// visual tracking of its cluster and LiDAR registration in later modules). Plain structs.
//
// A track holds one TrackFrame per frame from its birth to the last frame it was kept alive,
// consecutive and without holes: frames where it was not observed hold the motion model's
// prediction. Poses T_w_o are in the tracking frame "w": the world frame when camera poses
// are known, otherwise each frame's own camera frame (T_w_c = I), as AB3DMOT tracks.
// The twist xi of frame i links it to frame i + 1 (paper eq. 2, left-multiplied in w):
//   T_w_o(i+1) = exp(Pi xi_i) T_w_o(i).
#include <limits>
#include <string>
#include <vector>

#include "geometry/link_projection.hpp"
#include "geometry/types.hpp"
#include "objects/travel_direction.hpp"

namespace twistslam::objects {

enum class TrackState {
  kTentative,  // born, not yet observed often enough to be reported
  kConfirmed,  // observed in the last frame and reported
  kLost,       // confirmed once, missed in the last frame(s); predicted, may come back
  kDead,       // missed too long: no longer associated, kept for the results
};
const char* to_string(TrackState state);

struct TrackFrame {
  int frame = -1;
  Mat4 T_w_o = Mat4::Identity();  // estimate: detection, then window-smoothed
  Vec6 xi = Vec6::Zero();         // twist to the next frame (zero for the last frame)
  bool detected = false;          // a detection was associated in this frame
  Mat4 T_w_o_detected = Mat4::Identity();  // that detection's box pose, heading aligned
  // the detector's own heading of that box (its x axis in w, before the alignment); zero when
  // the detector knows the heading mod pi only (Detection::point_extent: the classical one)
  Vec3 detected_heading_w = Vec3::Zero();
  // for such a box beside the camera's lane and along its travel: the heading a parked car
  // there has by the traffic side's rule (ObjectLidarOptions::road_side_heading; zero: none)
  Vec3 road_side_heading_w = Vec3::Zero();
  Vec3 detected_size = Vec3::Zero();       // its l, w, h (m)
  double score = 0;               // its score (the detector's)
  double range = 0;               // its distance from the camera, m
  double confidence = 0;          // its range-corrected score (TrackerOptions)
  int detection_index = -1;       // its index in the frame's detection list
  // a box whose length is the detector's prior (Detection::open_end): the direction in w from
  // its seen face to the prior's end (zero for a measured length), and how far its centre was
  // moved that way to put that end at the track's length (update_size)
  Vec3 open_end_w = Vec3::Zero();
  double open_shift_m = 0;
  // a box that is the tight extent of its LiDAR points (Detection::point_extent) and measured
  // its length: the direction in w from its seen end (the one nearer the sensor) to its far
  // end, whose side returns thin out, so the length is a lower bound (zero otherwise). It
  // moves along it as an open end does (open_shift_m).
  Vec3 far_end_w = Vec3::Zero();
  bool reported = false;          // part of the output (set by the tracker's output policy)
  // the cluster was re-born from this frame's stereo points (ObjectTracker::reseed): no point
  // of it was seen in an earlier row
  bool reborn = false;
  // not reported because the LiDAR saw through its box (tracking/object_free_space.cpp): the
  // returns around the box's rays then (camera frame), to take the test again with the final
  // pose; empty otherwise
  Points3 see_through_returns;
  Vec3 see_through_centre_c = Vec3::Zero();  // the box centre (camera frame) then
  // not reported because its track's points lie nearer than the LiDAR sees them
  // (tracking/object_lidar_check.cpp); the verdict is taken again on the whole track at the end
  bool lidar_contradicted = false;
  // a far camera-only vehicle row: the LiDAR returns on its instance mask then (u, v px,
  // depth m), to scale the final rows' depth to them (tracking/object_lidar_align.cpp);
  // empty otherwise
  Points3 far_lidar_returns;
  // a nearer camera-only vehicle row: the depth (m, camera frame) of the face its instance
  // mask's LiDAR returns measured then (ObjectLidarOptions::far_lidar_align_surface_quantile of
  // their depths), to lift an origin left in front of it at the end
  // (tracking/object_lidar_align.cpp, lift_near_rows_onto_their_face); NaN otherwise
  double lidar_face_depth_m = std::numeric_limits<double>::quiet_NaN();
  // LiDAR registration (eq. 6-7): the object's motion in w from the previous frame to this
  // one, T_w_o(this) = M_w_registered T_w_o(previous), measured by GICP of the object scans
  bool registered = false;
  Mat4 M_w_registered = Mat4::Identity();
  // its sigmas (m/frame at the object's centre, rad/frame in the link's rotation), from
  // GICP's information; zero: e_reg uses the options' fixed sigmas
  Vec2 reg_sigma = Vec2::Zero();
  // or its whole covariance (objects/motion_uncertainty.hpp: eps with M_w -> exp(eps) M_w,
  // world twist [v; w] at the world origin, zero across the link); zero: the sigmas above
  Mat6 reg_covariance = Mat6::Zero();
  // the camera pose T_c_w this row's box and registration were put in w with (the visual
  // tracker's; identity for the detections tracker): the keyframe BA takes them back into
  // the camera frame, where they were measured
  Mat4 T_c_w = Mat4::Identity();

  bool has_detection() const { return detection_index >= 0; }
};

struct ObjectTrack {
  int id = -1;
  int class_id = -1;
  geometry::LinkType link = geometry::LinkType::kFree;
  Mat6 Pi = Mat6::Identity();  // the link's projector
  TrackState state = TrackState::kTentative;
  std::vector<TrackFrame> frames;  // consecutive frames, birth first
  // Output only: predictions before the first frame, oldest first, consecutive up to it
  // (the tracker's backcast of a far-born track; never detected, always reported).
  std::vector<TrackFrame> backcast;
  Vec3 size = Vec3::Zero();        // l, w, h: per-dimension median of the detections (paper)
  int hits = 0;                    // frames with an associated detection
  int misses = 0;                  // consecutive frames without one, up to the last frame
  int confirmed_frame = -1;        // frame at which it was confirmed (-1: never)
  TravelDirection travel;          // its direction of travel in the object frame (vehicles)
  // the object frame is the box frame of a 3D detection (canonical pose: origin at the box
  // centre, x along the length, y down), not the cluster's arbitrary first frame
  bool canonical = false;
  int canonical_frame = -1;        // the frame whose box set it
  bool heading_from_motion = false;  // its front was checked against the direction it moved
  // its rows before canonical_frame (a cluster's guesses) were re-placed once by the boxes
  bool birth_placed = false;
  // per object scan spanning its length (canonical vehicles, tracking/object_front_profile.cpp):
  // the hood-minus-trunk gap along the object frame's x axis (m; > 0: the front lies at +x)
  std::vector<double> front_profile_m;
  // per row checked against the LiDAR (camera-only vehicle rows, tracking/object_lidar_check.cpp):
  // the median over its points on its mask of the returns' depth around each over its own
  // depth, and of their difference (m)
  std::vector<double> lidar_depth_ratios;
  std::vector<double> lidar_depth_offsets_m;
  // per row, the pose the online tracking gave it before the final smoothing replaced T_w_o
  // (empty: not smoothed)
  std::vector<Mat4> T_w_o_online;
  // the same for the backcast rows the final smoothing re-placed (empty: not re-placed)
  std::vector<Mat4> backcast_online;

  bool alive() const { return state != TrackState::kDead; }
  bool ever_confirmed() const { return confirmed_frame >= 0; }
  const TrackFrame& last() const { return frames.back(); }
  TrackFrame& last() { return frames.back(); }
  int first_frame() const { return frames.empty() ? -1 : frames.front().frame; }
  // Frame row of dataset frame f, or nullptr.
  const TrackFrame* at(int frame) const;
  // The first row a point of the cluster may link to its later rows: the last row re-born
  // nearer than max_depth_m (camera z, m) with at least min_rows rows before it, else 0
  // (max_depth_m 0: always 0). Before it nothing but e_const links the rows to the cluster's
  // points: a window over them would carry them back from the new points' motion.
  int first_linked_row(double max_depth_m, int min_rows = 1) const;
  // Mean score of the associated detections (0 without any).
  double mean_score() const;
  // Track confidence: mean range-corrected score of the associated detections (0 without any).
  double confidence() const;
  // Recomputes `size` as the per-dimension median over the detected frames (the length over
  // those whose length was measured, if any; when every one of those is a point extent's lower
  // bound, their `bound_quantile` quantile instead), then moves every box whose length is the
  // prior along its open end, and every point extent along its far end, so that this end lies
  // at the track's length from its seen face.
  void update_size(double bound_quantile = 0.5);
};

}  // namespace twistslam::objects
