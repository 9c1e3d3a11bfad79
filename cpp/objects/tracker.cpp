#include "objects/tracker.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "geometry/box_overlap.hpp"
#include "geometry/se3.hpp"
#include "objects/assignment.hpp"
#include "objects/motion_model.hpp"

namespace twistslam::objects {

geometry::Box3D box_at(const Mat4& T_w_o, const Vec3& size) {
  geometry::Box3D b;
  b.center = T_w_o.block<3, 1>(0, 3);
  b.length = size[0];
  b.width = size[1];
  b.height = size[2];
  b.yaw = std::atan2(T_w_o(0, 2), T_w_o(0, 0));  // R = rot_y(yaw) for an upright box
  return b;
}

double range_corrected_score(double score, double range, const TrackerOptions& options) {
  return score + options.range_score_slope * std::max(0.0, range - options.range_score_start);
}

Tracker::Tracker(const TrackerOptions& options) : options_(options) {
  if (options_.window < 2) throw std::invalid_argument("tracker: window must be >= 2 frames");
  if (options_.backcast_frames < 0) throw std::invalid_argument("tracker: backcast_frames must be >= 0");
  if (!(options_.miss_turn_decay >= 0 && options_.miss_turn_decay <= 1))
    throw std::invalid_argument("tracker: miss_turn_decay must be in [0, 1]");
  if (!std::isfinite(options_.range_score_slope) || !std::isfinite(options_.range_score_start))
    throw std::invalid_argument("tracker: range_score_start and range_score_slope must be finite");
  if (options_.birth_hits < 1) throw std::invalid_argument("tracker: birth_hits must be >= 1");
  if (!(options_.ground_normal.norm() > 0) || !options_.ground_normal.allFinite())
    throw std::invalid_argument("tracker: ground_normal must be a finite non-zero vector");
}

int Tracker::num_live() const {
  int n = 0;
  for (const auto& t : tracks_) n += t.alive();
  return n;
}

namespace {
void check_input(int frame, int last_frame, const Mat4& T_w_c, const std::vector<Detection>& dets) {
  if (frame <= last_frame)
    throw std::invalid_argument("tracker: frame " + std::to_string(frame) +
                                " is not after the previous frame " + std::to_string(last_frame));
  if (!T_w_c.allFinite() || !geometry::is_rigid_transform(T_w_c, 1e-4))
    throw std::invalid_argument("tracker: T_w_c of frame " + std::to_string(frame) +
                                " is not a finite rigid transform");
  for (size_t i = 0; i < dets.size(); ++i) {
    const auto& b = dets[i].box;
    if (!b.center.allFinite() || !std::isfinite(b.yaw) || !std::isfinite(dets[i].score) || !b.valid())
      throw std::invalid_argument("tracker: detection " + std::to_string(i) + " of frame " +
                                  std::to_string(frame) +
                                  " has a non-finite value or a non-positive size");
  }
}
}  // namespace

void Tracker::step(int frame, const Mat4& T_w_c, const std::vector<Detection>& dets) {
  check_input(frame, last_frame_, T_w_c, dets);
  // Skipped frames: every live track is predicted (and counts a miss) until this frame.
  for (int f = last_frame_ + 1; last_frame_ >= 0 && f < frame; ++f) {
    predict_all(f);
    for (auto& t : tracks_)
      if (t.alive()) miss_track(t);
  }
  if (first_frame_ < 0) first_frame_ = frame;
  // camera poses by frame (skipped frames take this one), for the backcast's range check
  camera_poses_.resize(frame - first_frame_ + 1, T_w_c);
  last_frame_ = frame;
  predict_all(frame);

  std::vector<Mat4> T_w_det(dets.size());
  std::vector<geometry::Box3D> det_boxes(dets.size());
  std::vector<double> confidence(dets.size());  // range-corrected scores
  for (size_t j = 0; j < dets.size(); ++j) {
    T_w_det[j] = T_w_c * dets[j].box.pose();
    det_boxes[j] = box_at(T_w_det[j], Vec3(dets[j].box.length, dets[j].box.width, dets[j].box.height));
    confidence[j] = range_corrected_score(dets[j].score, dets[j].box.center.norm(), options_);
  }
  std::vector<int> live;
  for (int i = 0; i < static_cast<int>(tracks_.size()); ++i)
    if (tracks_[i].alive()) live.push_back(i);

  std::vector<char> track_done(tracks_.size(), 0), det_done(dets.size(), 0);
  // One association pass: `tracks` x `detections` (indices), gated at max_cost.
  const auto associate = [&](const std::vector<int>& tr, const std::vector<int>& de, double max_cost) {
    std::vector<geometry::Box3D> tb, db;
    std::vector<int> tc, dc;
    for (int i : tr) tb.push_back(box_at(tracks_[i].last().T_w_o, tracks_[i].size)), tc.push_back(tracks_[i].class_id);
    for (int j : de) db.push_back(det_boxes[j]), dc.push_back(dets[j].class_id);
    const auto cost = association_cost(tb, tc, db, dc, options_.metric);
    for (const auto& [r, c] : solve_assignment(cost, max_cost)) {
      const int i = tr[r], j = de[c];
      update_track(tracks_[i], T_w_det[j], dets[j], j, confidence[j]);
      track_done[i] = det_done[j] = 1;
    }
  };

  std::vector<int> high, low;
  for (int j = 0; j < static_cast<int>(dets.size()); ++j) {
    if (confidence[j] >= options_.high_score) high.push_back(j);
    else if (confidence[j] >= options_.low_score) low.push_back(j);
  }
  associate(live, high, options_.max_cost);
  if (options_.second_pass && !low.empty()) {
    std::vector<int> rest;  // unmatched tracks that were confirmed once: a weak detection
    for (int i : live)      // keeps a known object alive, but never makes a new one
      if (!track_done[i] && tracks_[i].ever_confirmed()) rest.push_back(i);
    associate(rest, low, options_.second_pass_max_cost);
  }
  for (int i : live)
    if (!track_done[i]) miss_track(tracks_[i]);
  for (int j : high)
    if (!det_done[j] && confidence[j] >= options_.birth_score) birth(frame, T_w_det[j], dets[j], j, confidence[j]);
}

void Tracker::predict_all(int frame) {
  for (auto& t : tracks_) {
    if (!t.alive()) continue;
    TrackFrame next;
    next.frame = frame;
    const TrackFrame& last = t.last();
    next.xi = last.xi;  // constant velocity until observed again...
    if (!last.detected && options_.miss_turn_decay < 1) {
      // ...but a turn rate from a few noisy box headings is not extrapolated for long: from
      // the first missed frame on, the rotation of the body-frame twist (the car's own yaw
      // rate) decays by miss_turn_decay per frame, its forward speed is kept.
      Vec6 body = geometry::se3_adjoint(geometry::se3_inverse(last.T_w_o)) * next.xi;
      body.tail<3>() *= options_.miss_turn_decay;
      next.xi = geometry::se3_adjoint(last.T_w_o) * body;
    }
    next.T_w_o = predict_pose(last.T_w_o, next.xi, t.Pi);
    t.frames.push_back(next);
  }
}

void Tracker::update_track(ObjectTrack& t, const Mat4& T_w_detected, const Detection& det, int index,
                           double confidence) {
  TrackFrame& f = t.last();
  // The same box with its heading turned by pi is one object, not a new one: align the
  // detection's heading with the track's (predicted) heading.
  f.T_w_o_detected = heading_flipped(T_w_detected, f.T_w_o) ? turned_around(T_w_detected) : T_w_detected;
  f.detected = true;
  f.detected_size = Vec3(det.box.length, det.box.width, det.box.height);
  f.score = det.score;
  f.range = det.box.center.norm();
  f.confidence = confidence;
  f.detection_index = index;
  f.T_w_o = f.T_w_o_detected;  // initial value; refined by the window
  // The frames missed since the previous detection held forward predictions: now that both
  // ends are known they are interpolated (constant twist from the last estimate to this
  // detection under the link), which the window then refines where it reaches.
  if (options_.interpolate_gaps && t.misses > 0) {
    const int n = static_cast<int>(t.frames.size());
    const int a = n - 1 - t.misses - 1;  // the last frame before the gap
    if (a >= 0) {
      const Mat4& T_a = t.frames[a].T_w_o;
      const Vec6 xi = t.Pi * geometry::twist_between(T_a, f.T_w_o);
      const double span = n - 1 - a;
      for (int k = a + 1; k < n - 1; ++k) t.frames[k].T_w_o = geometry::se3_exp(((k - a) / span) * xi) * T_a;
    }
  }
  ++t.hits;
  t.misses = 0;
  t.update_size();
  if (t.state == TrackState::kTentative && t.hits >= options_.birth_hits) t.confirmed_frame = f.frame;
  if (t.ever_confirmed()) t.state = TrackState::kConfirmed;
  optimize_window(t);
}

void Tracker::miss_track(ObjectTrack& t) {
  ++t.misses;
  if (t.state == TrackState::kTentative) {
    if (t.misses > options_.tentative_max_misses) t.state = TrackState::kDead;
  } else {
    t.state = t.misses > options_.max_misses ? TrackState::kDead : TrackState::kLost;
  }
  if (t.state == TrackState::kDead) {
    while (!t.frames.empty() && !t.last().detected) t.frames.pop_back();  // predictions only
    if (!t.frames.empty()) t.last().xi.setZero();
  }
}

void Tracker::birth(int frame, const Mat4& T_w_detected, const Detection& det, int index,
                    double confidence) {
  ObjectTrack t;
  t.id = next_id_++;
  t.class_id = det.class_id;
  t.link = det.planar ? geometry::LinkType::kPlanar : geometry::LinkType::kFree;
  t.Pi = det.planar ? geometry::projector_planar(options_.ground_normal) : geometry::projector_free();
  TrackFrame f;
  f.frame = frame;
  f.T_w_o = f.T_w_o_detected = T_w_detected;
  f.detected = true;
  f.detected_size = Vec3(det.box.length, det.box.width, det.box.height);
  f.score = det.score;
  f.range = det.box.center.norm();
  f.confidence = confidence;
  f.detection_index = index;
  t.frames.push_back(f);
  t.hits = 1;
  t.update_size();
  if (options_.birth_hits <= 1) {
    t.confirmed_frame = frame;
    t.state = TrackState::kConfirmed;
  }
  tracks_.push_back(std::move(t));
}

void Tracker::optimize_window(ObjectTrack& t) {
  const int n = static_cast<int>(t.frames.size());
  if (n < 2) return;
  if (options_.optimize) {
    // The window's free poses plus up to two fixed ones before it: e_const reaches back
    // across the window's start, so the smoothed trajectory stays continuous.
    const int first_free = std::max(0, n - options_.window);
    const int first = std::max(0, first_free - 2);
    std::vector<optim::ObjectWindowFrame> window;
    window.reserve(n - first);
    for (int k = first; k < n; ++k) {
      const TrackFrame& f = t.frames[k];
      optim::ObjectWindowFrame w;
      w.T_w_o = f.T_w_o;
      // without e_const nothing ties a frame without detection to the others (e_link only
      // restricts the direction of its motion): it keeps its interpolated / predicted pose
      w.fixed = k < first_free || (!f.detected && !options_.window_options.use_const);
      w.has_detection = f.detected;
      w.T_w_o_detected = f.T_w_o_detected;
      window.push_back(w);
    }
    const auto summary = optim::optimize_object_window(window, t.Pi, options_.window_options);
    if (summary.usable) {
      for (int k = first_free; k < n; ++k) t.frames[k].T_w_o = window[k - first].T_w_o;
    }
  }
  // Twists linking consecutive poses (eq. 2), restricted to the link.
  const int from = std::max(0, n - options_.window - 1);
  for (int k = from; k + 1 < n; ++k) t.frames[k].xi = t.Pi * geometry::twist_between(t.frames[k].T_w_o, t.frames[k + 1].T_w_o);
  t.last().xi = t.frames[n - 2].xi;
}

void Tracker::set_reported_flags() {
  for (auto& t : tracks_) {
    int last_detected = -1;
    for (int k = 0; k < static_cast<int>(t.frames.size()); ++k) {
      TrackFrame& f = t.frames[k];
      f.reported = false;
      if (!t.ever_confirmed() || !f.detected) continue;
      f.reported = options_.report_tentative_frames || f.frame >= t.confirmed_frame;
      // a short gap between two detections: its interpolated, smoothed poses are reported
      if (f.reported && last_detected >= 0 && k - last_detected - 1 <= options_.max_reported_gap)
        for (int g = last_detected + 1; g < k; ++g)
          t.frames[g].reported = options_.report_tentative_frames || t.frames[g].frame >= t.confirmed_frame;
      last_detected = k;
    }
  }
  for (auto& t : tracks_) set_backcast(t);
}

void Tracker::set_backcast(ObjectTrack& t) const {
  t.backcast.clear();
  if (!t.ever_confirmed() || t.frames.empty() || options_.backcast_frames <= 0) return;
  const TrackFrame& first = t.frames.front();
  if (!first.detected || first.range < options_.backcast_min_range) return;
  // Backwards under the link with the first twist (eq. 2 inverted): T(f-1) = exp(-Pi xi) T(f).
  // Stops at the first frame stepped; where the box comes nearer than backcast_min_range or
  // behind the camera (the detector would have seen it; a wild twist); and where it would
  // overlap a box another track reports (the object was already tracked: a fragment).
  const Vec6 xi = t.frames.size() > 1 ? t.frames.front().xi : Vec6::Zero();
  Mat4 T = first.T_w_o;
  for (int k = 1; k <= options_.backcast_frames; ++k) {
    const int frame = first.frame - k;
    if (frame < first_frame_) break;
    T = predict_pose(T, -xi, t.Pi);
    const Mat4 T_c_o = geometry::se3_inverse(camera_poses_[frame - first_frame_]) * T;
    const Vec3 p_c = T_c_o.block<3, 1>(0, 3);
    if (p_c.z() <= 0 || p_c.norm() < options_.backcast_min_range) break;
    const geometry::Box3D box = box_at(T, t.size);
    bool taken = false;
    for (const auto& other : tracks_) {
      if (&other == &t || other.class_id != t.class_id) continue;
      const TrackFrame* o = other.at(frame);
      if (o && o->reported && geometry::iou_bev(box, box_at(o->T_w_o, other.size)) > 0) {
        taken = true;
        break;
      }
    }
    if (taken) break;
    TrackFrame b;
    b.frame = frame;
    b.T_w_o = T;
    b.xi = xi;
    b.reported = true;
    t.backcast.push_back(b);
  }
  std::reverse(t.backcast.begin(), t.backcast.end());  // oldest first
}

const std::vector<ObjectTrack>& Tracker::tracks() {
  set_reported_flags();
  return tracks_;
}

}  // namespace twistslam::objects
