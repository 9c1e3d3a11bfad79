#pragma once
// 3D multi-object tracking from detections (the objects half of the paper, fed by a 3D
// detector only): per frame, predict every live track with its twist under its mechanical
// link (eq. 2), associate detections (Hungarian on a configurable cost, a second pass for
// low-score detections), update the associated tracks by a sliding-window optimisation of
// their poses (e_const, e_det, detection prior: cpp/optim/object_window.hpp), give birth to
// new tracks and let missed ones die. The state is ObjectTrack (object_track.hpp), shared
// with the visual and LiDAR object tracking of later modules.
#include <vector>

#include "geometry/box3d.hpp"
#include "objects/association.hpp"
#include "objects/detection.hpp"
#include "objects/object_track.hpp"
#include "optim/object_window.hpp"

namespace twistslam::objects {


// Defaults = twistslam.Config().objects (python/twistslam/config_objects.py says why each).
struct TrackerOptions {
  TrackerOptions() {
    window_options.link_sigma_translation = 0.1;  // camera -y is not the road normal
    window_options.max_iterations = 5;
    window_options.const_sigma_translation = 0.1;
  }
  AssociationMetric metric = AssociationMetric::kGiou3d;
  double max_cost = 1.2;              // first pass gate, in the metric's unit (GIoU > -0.2)
  bool second_pass = true;            // low-score detections against unmatched tracks
  double second_pass_max_cost = 1.0;  // its gate (GIoU > 0: overlap required)
  double high_score = 1.0;            // detections >= this take part in pass 1 and births
  double low_score = -1.0;            // detections >= this (and < high) in pass 2 only
  double birth_score = 3.0;           // an unmatched detection >= this starts a track
  int birth_hits = 2;                 // detections before a track is confirmed (K)
  int max_misses = 10;                // consecutive misses a confirmed track survives (M)
  int tentative_max_misses = 0;       // consecutive misses a tentative track survives
  Vec3 ground_normal = Vec3(0, -1, 0);  // planar link normal in the tracking frame (up)
  bool optimize = true;               // sliding-window optimisation after each association
  int window = 6;                     // frames in the window
  optim::ObjectWindowOptions window_options;
  bool report_tentative_frames = true;  // once confirmed, its earlier frames are reported
  int max_reported_gap = 10;          // missed frames inside a track reported (interpolated)
  bool interpolate_gaps = true;       // a re-detected track's missed frames are interpolated
  double miss_turn_decay = 0.0;       // per missed frame, factor of the predicted turn rate
  // Range-corrected detection score, what every score threshold (both passes, births) and the
  // track confidence see: score + range_score_slope * max(0, range - range_score_start), range
  // = distance of the box centre from the camera. A detector's score for a true object falls
  // with range (fewer LiDAR points), its false detections' scores do not.
  double range_score_start = 35.0;    // m
  double range_score_slope = 0.15;    // score per m (0: the raw score)
  // Backcast: a confirmed track whose first detection lies at least backcast_min_range from
  // the camera is reported up to backcast_frames frames before it, predicted backwards under
  // its link with its first twist (the detector picks far cars up late: the car was there).
  int backcast_frames = 8;            // frames (0: off)
  double backcast_min_range = 45.0;   // m
};

class Tracker {
 public:
  explicit Tracker(const TrackerOptions& options);

  // Processes one frame. `frame` must increase from call to call (skipped frames are
  // predicted). T_w_c: the camera pose in the tracking frame (identity to track in the
  // camera frame). std::invalid_argument for a frame out of order, a non-finite pose or a
  // detection with a non-finite value or a non-positive size.
  void step(int frame, const Mat4& T_w_c, const std::vector<Detection>& detections);

  // Every track ever born, dead ones included, with `reported` flags and `backcast` frames
  // set by the output policy (report_tentative_frames, max_reported_gap, backcast_*).
  const std::vector<ObjectTrack>& tracks();
  int num_live() const;
  int last_frame() const { return last_frame_; }
  const TrackerOptions& options() const { return options_; }

 private:
  void predict_all(int frame);
  void update_track(ObjectTrack& track, const Mat4& T_w_detected, const Detection& det, int index,
                    double confidence);
  void miss_track(ObjectTrack& track);
  void optimize_window(ObjectTrack& track);
  void birth(int frame, const Mat4& T_w_detected, const Detection& det, int index, double confidence);
  void set_reported_flags();
  void set_backcast(ObjectTrack& track) const;

  TrackerOptions options_;
  std::vector<ObjectTrack> tracks_;
  int next_id_ = 0;
  int first_frame_ = -1;  // the first frame stepped: no backcast before it
  std::vector<Mat4> camera_poses_;  // T_w_c of frames first_frame_ ... last_frame_
  int last_frame_ = -1;
};

// Box of size l, w, h at a pose T_w_o whose y axis is vertical (yaw about y).
geometry::Box3D box_at(const Mat4& T_w_o, const Vec3& size);

// The range-corrected score of a detection `range` metres from the camera (TrackerOptions).
double range_corrected_score(double score, double range, const TrackerOptions& options);

}  // namespace twistslam::objects
