// A new track's frames before its birth, from boxes (objects/box_chain.hpp). A cluster starts
// only once its instance holds enough stereo points; a far, dark or queued car may be boxed by
// the detector frames earlier. The boxes no track took are kept for backfill_frames frames, and
// a new canonical track takes the chain of them that lines up with its first box as backcast
// rows: reported poses (the boxes'), never tracked, never smoothed (object_track.hpp).
#include <algorithm>

#include "geometry/se3.hpp"
#include "objects/box_chain.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
namespace {

// Velocity (m per frame, forward in time) of a line through the track's first row and the
// boxes of its backcast rows (T_w_o_detected), by least squares: their scatter averages out.
Vec3 velocity_through_boxes(const objects::ObjectTrack& track) {
  const Vec3 p_first = track.frames.front().T_w_o.topRightCorner<3, 1>();
  Vec3 sum = Vec3::Zero();
  double sum_sq = 0;
  for (const objects::TrackFrame& row : track.backcast) {
    const double back = static_cast<double>(track.first_frame() - row.frame);
    sum += back * (p_first - row.T_w_o_detected.topRightCorner<3, 1>());
    sum_sq += back * back;
  }
  return sum / sum_sq;
}

// The backcast rows continue the first row backwards at this velocity, at its rotation.
void continue_backwards(objects::ObjectTrack& track, const Vec3& velocity) {
  const Mat4& T_first = track.frames.front().T_w_o;
  for (objects::TrackFrame& row : track.backcast) {
    row.T_w_o = T_first;
    row.T_w_o.topRightCorner<3, 1>() -= static_cast<double>(track.first_frame() - row.frame) * velocity;
  }
}

}  // namespace

void ObjectTracker::remember_unused_boxes(const Frame& frame) {
  if (lidar_options_.backfill_frames <= 0) {
    recent_unused_boxes_.clear();
    return;
  }
  // a gap in the frames (a lost camera) breaks the chain of consecutive frames
  if (!recent_unused_boxes_.empty() && recent_unused_boxes_.back().frame != frame.index - 1)
    recent_unused_boxes_.clear();
  UnusedBoxes now;
  now.frame = frame.index;
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  for (size_t d = 0; d < detections_.size(); ++d) {
    if (detection_used_[d]) continue;
    const objects::Detection& det = detections_[d];
    now.boxes.push_back({T_w_c * det.box.pose(), det.class_id, det.score, det.box.center.norm()});
  }
  recent_unused_boxes_.push_back(std::move(now));
  const size_t keep = static_cast<size_t>(lidar_options_.backfill_frames);
  if (recent_unused_boxes_.size() > keep)
    recent_unused_boxes_.erase(recent_unused_boxes_.begin(),
                               recent_unused_boxes_.end() - static_cast<long>(keep));
}

void ObjectTracker::backfill_from_boxes(int c) {
  objects::ObjectTrack& track = tracks_[c];
  if (lidar_options_.backfill_frames <= 0 || !track.canonical || track.frames.size() != 1 ||
      !track.backcast.empty() || recent_unused_boxes_.empty())
    return;
  const int first = track.first_frame();
  // candidates of frames first - 1, first - 2, ... (consecutive), of the track's class
  std::vector<std::vector<Vec3>> centres;
  std::vector<std::vector<const UnusedBox*>> boxes;
  for (auto it = recent_unused_boxes_.rbegin(); it != recent_unused_boxes_.rend(); ++it) {
    if (it->frame != first - 1 - static_cast<int>(centres.size())) break;
    centres.emplace_back();
    boxes.emplace_back();
    for (const UnusedBox& b : it->boxes) {
      if (b.class_id != track.class_id) continue;
      centres.back().push_back(b.T_w_box.topRightCorner<3, 1>());
      boxes.back().push_back(&b);
    }
  }
  objects::BoxChainOptions chain_options;
  chain_options.first_gate_m = lidar_options_.backfill_first_gate_m;
  chain_options.gate_m = lidar_options_.backfill_gate_m;
  chain_options.ambiguity_m = lidar_options_.backfill_ambiguity_m;
  const std::vector<int> chain =
      objects::box_chain(track.frames.front().T_w_o.topRightCorner<3, 1>(), centres, chain_options);
  if (chain.empty()) return;
  // The rows follow the boxes' mean motion, not each box: a box's own scatter (the oracle's
  // ~2 deg and 0.1-0.6 m) in every row raised the RPE of the tracks it was given (crowded s1
  // det-reg RPE_r 0.127 -> 0.408 deg/m with raw boxes). A car hardly turns in
  // backfill_frames frames: the first row's rotation.
  for (int s = static_cast<int>(chain.size()) - 1; s >= 0; --s) {  // oldest first
    const UnusedBox& b = *boxes[s][chain[s]];
    objects::TrackFrame row;
    row.frame = first - 1 - s;
    row.T_w_o_detected = b.T_w_box;  // kept for place_backcast (detection_index stays -1)
    row.reported = true;
    row.score = row.confidence = b.score;
    row.range = b.range;
    track.backcast.push_back(row);
  }
  continue_backwards(track, velocity_through_boxes(track));
}

void ObjectTracker::place_backcast(int c) {
  objects::ObjectTrack& track = tracks_[c];
  if (track.backcast.empty() || track.frames.size() < 2) return;
  // After the final smoothing moved the first row: a constant velocity continued backwards
  // from it at its rotation. From kMinBackcastBoxes boxes on, the velocity of a line through
  // them and the first row (their scatter averages out; a queued car that started moving
  // only when its cluster did was slower before: the track's own velocity carried it 0.5-1 m
  // off, crowded s1's car 17 ATE 0.011 -> 0.069 m, classical boxes; a constant acceleration
  // fitted to the boxes did no better with oracle boxes, 0.080 against 0.070 m); with fewer,
  // the track's first kBackcastSteps smoothed steps (one far box, 0.6 m off at 50 m, as a row
  // raised urban s0's far oncoming cars' ATE 0.045 -> 0.156 m).
  constexpr int kMinBackcastBoxes = 3;
  constexpr int kBackcastSteps = 4;
  Vec3 velocity = Vec3::Zero();
  if (static_cast<int>(track.backcast.size()) >= kMinBackcastBoxes) {
    velocity = velocity_through_boxes(track);
  } else {
    const int steps = std::min(kBackcastSteps, static_cast<int>(track.frames.size()) - 1);
    velocity = (track.frames[steps].T_w_o.topRightCorner<3, 1>() - track.frames.front().T_w_o.topRightCorner<3, 1>()) /
               static_cast<double>(steps);
  }
  track.backcast_online.clear();
  for (const objects::TrackFrame& row : track.backcast) track.backcast_online.push_back(row.T_w_o);
  continue_backwards(track, velocity);
}

}  // namespace twistslam::tracking
