// The object windows (paper eq. 9, the object terms with the cameras fixed): the sliding
// window after each tracked frame (its last window_frames rows, e_dyna + e_const + e_link +
// e_head + the LiDAR terms) and, once the sequence ends, the final smoothing of each whole
// track with every observation its points made. Both build the same
// optim::VisualObjectWindow (optim/visual_object_window.hpp) from the track's rows.
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "geometry/se3.hpp"
#include "objects/track_turn.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {

namespace {
// box pose priors that hold a window whose first pose is left free: two fix a planar track's
// position and heading where one box's noise (0.1 m, 2 deg) alone would
constexpr int kMinBoxesForFreeGauge = 2;
// a track born this many rows before its boxes keeps its early rows: the one-off window's
// cost grows with its rows (3 x the 8-frame window: ~1 ms more once per track)
constexpr int kMaxBirthWindowRows = 24;
// m, a birth row this far from the boxes' line is a wrong guess (urban s0's parked car: 6.6 m;
// the boxes' own noise and a few frames' extrapolation stay under 0.5 m)
constexpr double kBirthOffBoxesM = 1.0;

// Distance of the track's first pose from the line of its first two boxes (their centres'
// constant velocity carried back to the birth frame); 0 with fewer boxes.
double birth_off_boxes_m(const objects::ObjectTrack& track) {
  const objects::TrackFrame* box[2] = {nullptr, nullptr};
  for (const objects::TrackFrame& row : track.frames) {
    if (!row.has_detection()) continue;
    if (!box[0]) box[0] = &row;
    else if (!box[1]) box[1] = &row;
  }
  if (!box[1]) return 0.0;
  const Vec3 c0 = box[0]->T_w_o_detected.topRightCorner<3, 1>();
  const Vec3 v = (box[1]->T_w_o_detected.topRightCorner<3, 1>() - c0) / (box[1]->frame - box[0]->frame);
  const Vec3 predicted = c0 + v * (track.frames[0].frame - box[0]->frame);
  return (track.frames[0].T_w_o.topRightCorner<3, 1>() - predicted).norm();
}

int count_boxes(const objects::ObjectTrack& track) {
  int boxes = 0;
  for (const objects::TrackFrame& row : track.frames) boxes += row.has_detection();
  return boxes;
}

// The observations of point p in the window's frames [first_frame, first_frame + rows) as
// window point `index`; false when it has none there. With `in_front_of` (the window's camera
// and object poses), only those of a point in front of that frame's camera: an archived
// observation of a frame long past can lie behind it once the point moved with later
// refinements, and the reprojection is not defined there (the window's min_depth).
bool add_observations(const std::vector<objects::ObjectPointObservation>& seen, int first_frame,
                      int rows, int index, const Vec3& X_o, const LevelWeights& weights,
                      const optim::VisualObjectWindow* in_front_of, double min_depth,
                      std::vector<optim::VisualObjectObservation>* out) {
  bool any = false;
  for (const auto& o : seen) {
    const int f = o.frame - first_frame;
    if (f < 0 || f >= rows) continue;
    if (in_front_of) {
      const Mat4 T_c_o = in_front_of->T_c_w[f] * in_front_of->T_w_o[f];
      if ((T_c_o.topLeftCorner<3, 3>() * X_o + T_c_o.topRightCorner<3, 1>()).z() <= min_depth) continue;
    }
    out->push_back({f, index, o.uv, o.u_right, weights.at(o.octave)});
    any = true;
  }
  return any;
}
}  // namespace

optim::VisualObjectWindowOptions ObjectTracker::window_options(const objects::ObjectTrack& track) const {
  optim::VisualObjectWindowOptions wo;
  wo.use_detection_twist = lidar_options_.use_detection_twist;
  wo.det_sigma_translation = lidar_options_.det_sigma_translation;
  wo.det_sigma_rotation = lidar_options_.det_sigma_rotation;
  wo.use_detection_pose = lidar_options_.use_detection_pose && track.canonical;
  wo.det_pose_sigma_translation = lidar_options_.det_pose_sigma_translation;
  wo.det_pose_sigma_rotation = lidar_options_.det_pose_sigma_rotation;
  wo.huber_det = lidar_options_.huber_det;
  wo.det_sigma_reference_range_m = lidar_options_.det_sigma_reference_range_m;
  wo.use_registration = lidar_options_.use_registration;
  wo.reg_sigma_translation = lidar_options_.reg_sigma_translation;
  wo.reg_sigma_rotation = lidar_options_.reg_sigma_rotation;
  wo.huber_reg = lidar_options_.huber_reg;
  wo.use_heading = options_.nonholonomic;
  wo.lateral_sigma = options_.lateral_sigma_m;
  wo.axis_free_heading_min_step_m = options_.axis_free_heading_min_step_m;
  wo.axis_free_heading_min_chord_m = options_.axis_free_heading_min_chord_m;
  wo.use_const = options_.use_const;
  wo.const_sigma_translation = options_.const_sigma_translation;
  wo.const_sigma_rotation = options_.const_sigma_rotation;
  wo.const_rotation_reference_step_m = options_.const_rotation_reference_step_m;
  wo.const_rotation_min_fraction = options_.const_rotation_min_fraction;
  // a box frames a canonical track; a camera-only track's motion may be unobserved
  wo.rest_sigma_translation = track.canonical ? 0.0 : options_.rest_sigma_translation;
  wo.max_iterations = options_.window_iterations;
  wo.function_tolerance = options_.window_function_tolerance;
  return wo;
}

bool ObjectTracker::build_window(int c, int first, int rows, const std::map<int, Mat4>& camera_of,
                                 bool whole_life, optim::VisualObjectWindow* w,
                                 std::vector<int>* used) const {
  const objects::ObjectTrack& track = tracks_[c];
  const objects::ObjectCluster& cluster = clusters_[c];
  for (int r = first; r < first + rows; ++r) {
    const auto cam = camera_of.find(track.frames[r].frame);
    if (cam == camera_of.end()) return false;  // a frame without a camera pose (lost)
    w->T_c_w.push_back(cam->second);
    w->T_w_o.push_back(track.frames[r].T_w_o);
  }
  const int first_frame = track.frames[first].frame;
  const double min_depth = optim::VisualObjectWindowOptions().min_depth;
  if (!whole_life) {
    for (int i = 0; i < static_cast<int>(cluster.points.size()); ++i) {
      const objects::ObjectPoint& p = cluster.points[i];
      if (!add_observations(p.history, first_frame, rows, static_cast<int>(w->X_o.size()), p.X_o,
                            weights_, nullptr, min_depth, &w->observations))
        continue;
      used->push_back(i);
      w->X_o.push_back(p.X_o);
    }
  } else {
    // every point the track ever had (retired ones too), the longest-seen first; a point joins
    // while one of the frames it was seen in has fewer than smoothing_frame_observations. A car
    // tracked for 100 frames collects ~2000 points and 18k observations, most of them
    // short-lived and adding solver time rather than information
    std::vector<int> order;  // i: live point i, -1 - k: retired point k
    for (int i = 0; i < static_cast<int>(cluster.points.size()); ++i) order.push_back(i);
    for (int k = 0; k < static_cast<int>(cluster.retired.size()); ++k) order.push_back(-1 - k);
    auto point = [&](int code) -> const objects::ObjectPoint& {
      return code >= 0 ? cluster.points[code] : cluster.retired[-1 - code];
    };
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return point(a).archive.size() > point(b).archive.size();
    });
    const int quota = options_.smoothing_frame_observations;
    std::vector<int> per_frame(rows, 0);
    for (int code : order) {
      const objects::ObjectPoint& p = point(code);
      if (quota > 0) {
        bool needed = false;
        for (const auto& o : p.archive) {
          const int f = o.frame - first_frame;
          needed |= f >= 0 && f < rows && per_frame[f] < quota;
        }
        if (!needed) continue;
      }
      const size_t before = w->observations.size();
      if (!add_observations(p.archive, first_frame, rows, static_cast<int>(w->X_o.size()), p.X_o,
                            weights_, w, min_depth, &w->observations))
        continue;
      for (size_t e = before; e < w->observations.size(); ++e) ++per_frame[w->observations[e].frame];
      used->push_back(code);
      w->X_o.push_back(p.X_o);
    }
  }
  if (options_.nonholonomic && track.link == geometry::LinkType::kPlanar) {
    w->travel_axis_o = track.travel.axis(options_.travel_min_path_m, options_.travel_min_anisotropy,
                                         options_.travel_min_straightness);
    w->up_w = up_w_;
    w->wheeled = true;
  }
  // LiDAR terms: the boxes of the window's frames (e_det; the pose prior only where the
  // object frame is the box frame) and the registered motions (e_reg)
  for (int r = first; r < first + rows; ++r) {
    const objects::TrackFrame& row = track.frames[r];
    w->T_w_det.push_back(row.T_w_o_detected);
    w->has_detection.push_back(row.has_detection());
    // M_w_reg[i] links window frame i to i + 1: stored on the later row
    const bool next = r + 1 < first + rows && track.frames[r + 1].registered;
    w->M_w_reg.push_back(next ? track.frames[r + 1].M_w_registered : Mat4::Identity());
    w->has_registration.push_back(next);
    w->reg_sigma.push_back(next ? track.frames[r + 1].reg_sigma : Vec2::Zero());
    w->reg_covariance.push_back(next ? track.frames[r + 1].reg_covariance : Mat6::Zero());
  }
  return true;
}

bool ObjectTracker::take_window(int c, int first, const optim::VisualObjectWindow& w,
                                const std::vector<int>& used) {
  objects::ObjectTrack& track = tracks_[c];
  objects::ObjectCluster& cluster = clusters_[c];
  const int rows = static_cast<int>(w.T_w_o.size());
  // an under-constrained window (few points, no e_const) can throw poses kilometres away;
  // a large correction of a pose is fine (a far cluster's first pose is metres off in depth),
  // a step between consecutive poses beyond max_step_m is no motion
  for (int r = 1; r < rows; ++r) {
    const int frames_apart = track.frames[first + r].frame - track.frames[first + r - 1].frame;
    if ((w.T_w_o[r].topRightCorner<3, 1>() - w.T_w_o[r - 1].topRightCorner<3, 1>()).norm() >
        options_.max_step_m * frames_apart)
      return false;
  }
  for (int r = w.num_fixed_frames; r < rows; ++r) track.frames[first + r].T_w_o = w.T_w_o[r];
  for (int r = 0; r + 1 < rows; ++r)  // eq. 2: the twist linking consecutive poses
    track.frames[first + r].xi = track.Pi * geometry::twist_between(w.T_w_o[r], w.T_w_o[r + 1]);
  cluster.velocity = track.frames[first + rows - 2].xi;
  // A point a window moves farther than window_max_point_move_depth_ratio of its depth from
  // where it joined the cluster is no point of the object: it keeps its place and the next
  // cull drops it. A stereo depth is good to a few percent; such points were free along their
  // rays (depth-filled mask pixels seen in the left image only, an object moving along the
  // line of sight leaving no parallax) or matched on a surface behind the object, and ran to
  // hundreds of metres, window after window (crowded seeds: camera-only boxes 49-1600 m long,
  // a ghost's origin 3 m beyond its car). From where it joined, not from the last window: a
  // limit per window let a point creep away by steps. Not for a canonical track: its boxes
  // place it, and culling there cost the classical row RPE_r (0.147 -> 0.156 deg/m)
  const Mat4 T_c_o_last = w.T_c_w[rows - 1] * w.T_w_o[rows - 1];
  for (size_t k = 0; k < used.size(); ++k) {
    objects::ObjectPoint& p = used[k] >= 0 ? cluster.points[used[k]] : cluster.retired[-1 - used[k]];
    const double depth = std::abs(detail::transform(T_c_o_last, p.X_o_placed).z());
    const double max_move = options_.window_max_point_move_depth_ratio * depth;
    if (!track.canonical && (w.X_o[k] - p.X_o_placed).norm() > max_move) {
      p.found = 0;
      p.visible = std::max(p.visible, options_.cull_after_visible);
      continue;
    }
    p.X_o = w.X_o[k];
  }
  return true;
}

void ObjectTracker::refine_window(int c) {
  objects::ObjectTrack& track = tracks_[c];
  const int num_rows = static_cast<int>(track.frames.size());
  // once per track: its rows from birth to the first box were a cluster's guesses (a parked
  // car at 37 m: 4-7 m off in depth). Held fixed as a window's gauge they dragged the next ten
  // frames with them; one window over the whole track, its first pose free, lets the boxes
  // place them (e_const carries the motion back), then windows go on from settled rows.
  // Only where the birth row is off the boxes' line (box noise 0.1-0.3 m): placing rows by
  // noisy boxes with a free gauge turned oncoming cars whose guesses were fine.
  const int boxes = count_boxes(track);
  const bool place_birth = track.canonical && !track.birth_placed &&
                           lidar_options_.use_detection_pose &&
                           track.frames[0].frame < track.canonical_frame &&
                           boxes >= kMinBoxesForFreeGauge && num_rows <= kMaxBirthWindowRows &&
                           birth_off_boxes_m(track) > kBirthOffBoxesM;
  if (track.canonical && boxes >= kMinBoxesForFreeGauge) track.birth_placed = true;
  const int barrier =
      track.first_linked_row(options_.reborn_barrier_max_depth_m, options_.reborn_barrier_min_rows);
  const int first =
      std::max(place_birth ? 0 : num_rows - std::min<int>(options_.window_frames, num_rows), barrier);
  const int rows = num_rows - first;
  if (rows < 3) return;
  optim::VisualObjectWindow w;
  std::vector<int> used;
  if (!build_window(c, first, rows, T_c_w_of_frame_, false, &w, &used)) return;
  if (place_birth) w.num_fixed_frames = 0;  // the boxes hold the gauge
  if (!optim::refine_visual_object_window(camera_, w, track.Pi, window_options(track)).usable) return;
  take_window(c, first, w, used);
}

ObjectSmoothingReport ObjectTracker::smooth_tracks(const std::map<int, Mat4>& T_c_w_of_frame) {
  ObjectSmoothingReport report;
  if (!options_.final_smoothing) {
    retest_see_through(T_c_w_of_frame);
    retest_lidar_contradiction();
    align_far_rows_to_lidar(T_c_w_of_frame);
    bound_camera_only_turns();
    return report;
  }
  for (int c = 0; c < static_cast<int>(tracks_.size()); ++c) {
    objects::ObjectTrack& track = tracks_[c];
    const int num_rows = static_cast<int>(track.frames.size());
    if (num_rows < 3 || !track.ever_confirmed() || !track.T_w_o_online.empty()) continue;
    // a cluster never tracked (no valid twist since its birth: hits < 2) and without boxes
    // has no point seen in two frames, each row is one frame's stereo (its re-seeds): nothing
    // links the rows but e_const, which extrapolated them from the last re-seed's points.
    // Urban seed 4's track 41, a far car: its reported rows 0.3-2.5 m from the car online,
    // 1.6-3.7 m smoothed (a ghost)
    if (track.hits < 2 && count_boxes(track) == 0) continue;
    const int first =
        track.first_linked_row(options_.reborn_barrier_max_depth_m, options_.reborn_barrier_min_rows);
    const int rows = num_rows - first;
    if (rows < 3) continue;
    optim::VisualObjectWindow w;
    std::vector<int> used;
    if (!build_window(c, first, rows, T_c_w_of_frame, true, &w, &used)) continue;
    // the gauge: the boxes' pose priors where they frame the object (as the birth placement),
    // else one row held fixed (a cluster's frame is one of its poses; the points follow it)
    const bool boxes_hold = track.canonical && lidar_options_.use_detection_pose &&
                            count_boxes(track) >= kMinBoxesForFreeGauge;
    w.num_fixed_frames = 0;
    if (!boxes_hold) {
      // the gauge: the row seen through the most observations. A far track's first rows are
      // its least settled (a birth pose metres and degrees off), and the travel axis e_head
      // holds was learned in the frame of its later rows: held fixed, a wrong first row
      // turned every row against that axis (urban s2's oncoming car 9: 19 deg at birth)
      std::vector<int> seen(rows, 0);
      for (const auto& o : w.observations) ++seen[o.frame];
      w.gauge_frame = static_cast<int>(std::max_element(seen.rbegin(), seen.rend()).base() - seen.begin()) - 1;
    }
    optim::VisualObjectWindowOptions wo = window_options(track);
    wo.max_iterations = options_.smoothing_iterations;
    // Ceres' default, not the window's looser one: with boxes the whole-track problem gains
    // from its iterations (config.py, smoothing_iterations and window_function_tolerance)
    wo.function_tolerance = optim::VisualObjectWindowOptions().function_tolerance;
    // with LiDAR terms, the boxes and scans carry the motion; a point's errors repeat over
    // the frames that see it, which one problem over the whole track would count as
    // independent (ObjectLidarOptions::smoothing_keypoint_sigma_scale)
    bool lidar_terms = false;
    for (const objects::TrackFrame& row : track.frames) lidar_terms |= row.has_detection() || row.registered;
    if (lidar_terms) wo.reprojection_sigma_scale = lidar_options_.smoothing_keypoint_sigma_scale;
    const optim::VisualObjectWindowSummary s = optim::refine_visual_object_window(camera_, w, track.Pi, wo);
    if (!s.usable) continue;
    // a camera-only track that the smoothing moves off its online rows as a whole, not just
    // at a far birth, was pulled off its car (config.py, smoothing_max_median_move_m)
    if (!track.canonical && options_.smoothing_max_median_move_m > 0) {
      std::vector<double> moves_m;
      for (int r = 0; r < rows; ++r)
        if (track.frames[first + r].reported)
          moves_m.push_back((w.T_w_o[r].topRightCorner<3, 1>() - track.frames[first + r].T_w_o.topRightCorner<3, 1>()).norm());
      if (!moves_m.empty() && detail::median_value(moves_m) > options_.smoothing_max_median_move_m) {
        ++report.num_rejected;
        continue;
      }
    }
    std::vector<Mat4> online;
    online.reserve(num_rows);
    for (const objects::TrackFrame& row : track.frames) online.push_back(row.T_w_o);
    if (!take_window(c, first, w, used)) {
      ++report.num_rejected;
      continue;
    }
    place_backcast(c);  // the rows before the first (boxes' backfill) continue the smoothed ones
    track.T_w_o_online = std::move(online);
    ++report.num_tracks;
    report.num_residuals += s.num_residuals;
  }
  retest_see_through(T_c_w_of_frame);
  retest_lidar_contradiction();
  align_far_rows_to_lidar(T_c_w_of_frame);
  bound_camera_only_turns();
  return report;
}

void ObjectTracker::bound_camera_only_turns() {
  // last: the checks above project the points with the rows' rotations as the windows left them
  for (objects::ObjectTrack& track : tracks_) {
    if (track.link != geometry::LinkType::kPlanar || track.canonical) continue;
    objects::bound_turn_by_travel(&track, options_.min_turn_radius_m);
    objects::level_turn_off_its_path(&track, up_w_, options_.path_turn_chord_m,
                                     options_.path_turn_max_straight_deg,
                                     options_.path_turn_min_excess_deg);
  }
}

}  // namespace twistslam::tracking
