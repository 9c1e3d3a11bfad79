// The life cycle of an object cluster (paper sec. "Clusters creation"): new clusters from
// instance masks (at the ground-contact depth where stereo fails), points joining and being
// culled, re-seeding after a failure, the sliding window of e_dyna + e_const + e_head, the
// travel direction, and re-centring of the object frame. Search and twist
// estimation are in object_tracker.cpp.
#include <algorithm>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "optim/visual_object_window.hpp"
#include "tracking/ground_contact.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {

using detail::contains;
using detail::median_point;
using detail::observe;
using detail::transform;

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
}  // namespace

std::vector<std::pair<int, Vec3>> ObjectTracker::free_instance_points(const Frame& frame,
                                                                      int instance) const {
  std::vector<std::pair<int, Vec3>> out;
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  const map::StereoKeypoints& k = frame.keypoints;
  for (int i = 0; i < static_cast<int>(k.size()); ++i) {
    if (instance_of_keypoint_[i] != instance || claimed_by_[i] >= 0 || !k.has_depth(i) ||
        k.depth[i] > options_.max_depth_m)
      continue;
    out.emplace_back(i, transform(T_w_c, camera_.backproject(k.uv[i], k.depth[i])));
  }
  return out;
}

int ObjectTracker::min_seed_points(geometry::LinkType link) const {
  return link == geometry::LinkType::kPlanar ? options_.min_new_planar_cluster_points
                                             : options_.min_new_cluster_points;
}

std::vector<std::pair<int, Vec3>> ObjectTracker::ground_contact_points(const Frame& frame,
                                                                       int instance) const {
  std::vector<std::pair<int, Vec3>> out;
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  const GroundContact contact =
      ground_contact_depth(instances_, labels_, instance, options_.road_class_id, camera_, T_w_c,
                           road_plane_w_, options_.min_contact_columns,
                           options_.min_contact_fraction, options_.max_depth_m);
  if (!contact.valid) return out;
  const map::StereoKeypoints& k = frame.keypoints;
  for (int i = 0; i < static_cast<int>(k.size()); ++i) {
    if (instance_of_keypoint_[i] != instance || claimed_by_[i] >= 0 || k.has_depth(i)) continue;
    out.emplace_back(i, transform(T_w_c, camera_.backproject(k.uv[i], contact.depth)));
  }
  return out;
}

bool ObjectTracker::seed_points(const Frame& frame, int instance, int min_points,
                                bool ground_contact, std::vector<std::pair<int, Vec3>>* kept,
                                Vec3* centroid) const {
  auto fresh = free_instance_points(frame, instance);
  if (static_cast<int>(fresh.size()) < min_points && ground_contact && options_.ground_contact &&
      !labels_.empty() && road_plane_w_.head<3>().norm() > 0) {
    const auto mono = ground_contact_points(frame, instance);
    // the stereo points keep their depth: they place the car where they can
    fresh.insert(fresh.end(), mono.begin(), mono.end());
  }
  if (static_cast<int>(fresh.size()) < min_points) return false;
  std::vector<Vec3> X;
  for (const auto& f : fresh) X.push_back(f.second);
  const Vec3 median = median_point(X);
  kept->clear();
  *centroid = Vec3::Zero();
  for (const auto& f : fresh)
    if ((f.second - median).norm() <= options_.max_point_spread_m) kept->push_back(f), *centroid += f.second;
  if (static_cast<int>(kept->size()) < min_points) return false;
  *centroid /= static_cast<double>(kept->size());
  return true;
}

void ObjectTracker::append_point(objects::ObjectCluster& cluster, int c, const Frame& frame, int k,
                                 const Vec3& X_o) {
  objects::ObjectPoint p;
  p.X_o = X_o;
  p.descriptor = frame.keypoints.descriptors[k];
  observe(p, {frame.index, frame.keypoints.uv[k], frame.keypoints.u_right[k], frame.keypoints.octave[k]},
          options_.window_frames);
  p.class_votes.add(frame.keypoints.label[k]);
  cluster.points.push_back(p);
  claimed_by_[k] = c;
}

void ObjectTracker::add_points(int c, const Frame& frame, int instance) {
  objects::ObjectCluster& cluster = clusters_[c];
  if (static_cast<int>(cluster.points.size()) >= options_.max_points) return;
  const auto fresh = free_instance_points(frame, instance);
  if (fresh.empty()) return;
  const Mat4 T_o_w = geometry::se3_inverse(tracks_[c].last().T_w_o);
  std::vector<Vec3> existing;
  for (const auto& p : cluster.points) existing.push_back(p.X_o);
  const Vec3 centre = existing.empty() ? Vec3::Zero() : median_point(existing);
  for (const auto& [k, X_w] : fresh) {
    if (static_cast<int>(cluster.points.size()) >= options_.max_points) break;
    const Vec3 X_o = transform(T_o_w, X_w);
    if ((X_o - centre).norm() > options_.max_point_spread_m) continue;
    append_point(cluster, c, frame, k, X_o);
  }
}

bool ObjectTracker::reseed(int c, const Frame& frame, int instance, Mat4* T_w_o) {
  std::vector<std::pair<int, Vec3>> kept;
  Vec3 centroid;
  const bool vehicle = tracks_[c].link == geometry::LinkType::kPlanar;
  if (!seed_points(frame, instance, min_seed_points(tracks_[c].link), vehicle, &kept, &centroid))
    return false;
  objects::ObjectCluster& cluster = clusters_[c];
  // A cluster without a velocity yet (it failed in its second frame) has no prediction worth
  // keeping: its origin moves to the new points' centroid, as a new cluster's would, and its
  // one-frame-old points go. An older cluster keeps its points at the predicted pose: they
  // hold its extent (the box until detections give sizes), and the unmatched ones are culled.
  if (cluster.velocity.isZero() && !tracks_[c].canonical) {  // a canonical origin is its box's
    T_w_o->topRightCorner<3, 1>() = centroid;
    cluster.points.clear();
  }
  const Mat4 T_o_w = geometry::se3_inverse(*T_w_o);
  for (const auto& [k, X_w] : kept) {
    if (static_cast<int>(cluster.points.size()) >= options_.max_points) break;
    append_point(cluster, c, frame, k, transform(T_o_w, X_w));
  }
  return true;
}

bool ObjectTracker::start_cluster(const Frame& frame, int instance, int class_id, const Vec3& up_w) {
  std::vector<std::pair<int, Vec3>> kept;
  Vec3 centroid;
  const bool planar = contains(options_.planar_class_ids, class_id);
  const geometry::LinkType link = planar ? geometry::LinkType::kPlanar : geometry::LinkType::kFree;
  if (!seed_points(frame, instance, min_seed_points(link), planar, &kept, &centroid)) return false;

  objects::ObjectTrack track;
  track.id = next_id_++;
  track.class_id = class_id;
  track.link = link;
  track.Pi = planar ? geometry::projector_planar(up_w) : geometry::projector_free();
  track.state = objects::TrackState::kTentative;
  objects::TrackFrame row;
  row.frame = frame.index;
  row.T_w_o.topRightCorner<3, 1>() = centroid;  // identity rotation at the centroid (issue 10)
  row.detected = true;
  row.reported = true;
  track.frames.push_back(row);
  track.hits = 1;
  track.confirmed_frame = frame.index;
  track.state = objects::TrackState::kConfirmed;

  objects::ObjectCluster cluster;
  cluster.track_id = track.id;
  cluster.instance = instance;
  cluster.class_votes.add(class_id);
  const int c = static_cast<int>(clusters_.size());
  for (const auto& [k, X_w] : kept) {
    if (static_cast<int>(cluster.points.size()) >= options_.max_points) break;
    append_point(cluster, c, frame, k, X_w - centroid);
  }
  tracks_.push_back(std::move(track));
  clusters_.push_back(std::move(cluster));
  return true;
}

void ObjectTracker::refine_window(int c) {
  objects::ObjectTrack& track = tracks_[c];
  objects::ObjectCluster& cluster = clusters_[c];
  const int num_rows = static_cast<int>(track.frames.size());
  // once per track: its rows from birth to the first box were a cluster's guesses (a parked
  // car at 37 m: 4-7 m off in depth). Held fixed as a window's gauge they dragged the next ten
  // frames with them; one window over the whole track, its first pose free, lets the boxes
  // place them (e_const carries the motion back), then windows go on from settled rows.
  // Only where the birth row is off the boxes' line (box noise 0.1-0.3 m): placing rows by
  // noisy boxes with a free gauge turned oncoming cars whose guesses were fine.
  int boxes = 0;
  for (const objects::TrackFrame& row : track.frames) boxes += row.has_detection();
  const bool place_birth = track.canonical && !track.birth_placed &&
                           lidar_options_.use_detection_pose &&
                           track.frames[0].frame < track.canonical_frame &&
                           boxes >= kMinBoxesForFreeGauge && num_rows <= kMaxBirthWindowRows &&
                           birth_off_boxes_m(track) > kBirthOffBoxesM;
  if (track.canonical && boxes >= kMinBoxesForFreeGauge) track.birth_placed = true;
  const int rows = place_birth ? num_rows : std::min<int>(options_.window_frames, num_rows);
  if (rows < 3) return;
  const int first = num_rows - rows;
  optim::VisualObjectWindow w;
  for (int r = first; r < first + rows; ++r) {
    const auto cam = T_c_w_of_frame_.find(track.frames[r].frame);
    if (cam == T_c_w_of_frame_.end()) return;  // a frame without a camera pose (lost)
    w.T_c_w.push_back(cam->second);
    w.T_w_o.push_back(track.frames[r].T_w_o);
  }
  const int first_frame = track.frames[first].frame;
  std::vector<int> used;  // cluster point index per window point
  for (int i = 0; i < static_cast<int>(cluster.points.size()); ++i) {
    const objects::ObjectPoint& p = cluster.points[i];
    bool any = false;
    for (const auto& o : p.history) {
      const int f = o.frame - first_frame;
      if (f < 0 || f >= rows) continue;
      if (!any) used.push_back(i), w.X_o.push_back(p.X_o), any = true;
      w.observations.push_back({f, static_cast<int>(w.X_o.size()) - 1, o.uv, o.u_right,
                                weights_.at(o.octave)});
    }
  }
  if (options_.nonholonomic && track.link == geometry::LinkType::kPlanar) {
    w.travel_axis_o = track.travel.axis(options_.travel_min_path_m, options_.travel_min_anisotropy);
    w.up_w = up_w_;
  }
  // LiDAR terms: the boxes of the window's frames (e_det; the pose prior only where the
  // object frame is the box frame) and the registered motions (e_reg)
  for (int r = first; r < first + rows; ++r) {
    const objects::TrackFrame& row = track.frames[r];
    w.T_w_det.push_back(row.T_w_o_detected);
    w.has_detection.push_back(row.has_detection());
    // M_w_reg[i] links window frame i to i + 1: stored on the later row
    const bool next = r + 1 < first + rows && track.frames[r + 1].registered;
    w.M_w_reg.push_back(next ? track.frames[r + 1].M_w_registered : Mat4::Identity());
    w.has_registration.push_back(next);
    w.reg_sigma.push_back(next ? track.frames[r + 1].reg_sigma : Vec2::Zero());
  }
  if (place_birth) w.num_fixed_frames = 0;  // the boxes hold the gauge
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
  wo.use_const = options_.use_const;
  wo.const_sigma_translation = options_.const_sigma_translation;
  wo.const_sigma_rotation = options_.const_sigma_rotation;
  wo.const_rotation_reference_step_m = options_.const_rotation_reference_step_m;
  wo.const_rotation_min_fraction = options_.const_rotation_min_fraction;
  wo.max_iterations = options_.window_iterations;
  if (!optim::refine_visual_object_window(camera_, w, track.Pi, wo).usable) return;
  // an under-constrained window (few points, no e_const) can throw poses kilometres away;
  // a large correction of a pose is fine (a far cluster's first pose is metres off in depth),
  // a step between consecutive poses beyond max_step_m is no motion
  for (int r = 1; r < rows; ++r) {
    const int frames_apart = track.frames[first + r].frame - track.frames[first + r - 1].frame;
    if ((w.T_w_o[r].topRightCorner<3, 1>() - w.T_w_o[r - 1].topRightCorner<3, 1>()).norm() >
        options_.max_step_m * frames_apart)
      return;
  }
  for (int r = w.num_fixed_frames; r < rows; ++r) track.frames[first + r].T_w_o = w.T_w_o[r];
  for (int r = 0; r + 1 < rows; ++r)  // eq. 2: the twist linking consecutive poses
    track.frames[first + r].xi = track.Pi * geometry::twist_between(w.T_w_o[r], w.T_w_o[r + 1]);
  cluster.velocity = track.frames[first + rows - 2].xi;
  for (size_t k = 0; k < used.size(); ++k) cluster.points[used[k]].X_o = w.X_o[k];
}

void ObjectTracker::add_travel_step(objects::ObjectTrack& track) const {
  if (track.link != geometry::LinkType::kPlanar || track.frames.size() < 2) return;
  const objects::TrackFrame& prev = track.frames[track.frames.size() - 2];
  const objects::TrackFrame& cur = track.frames.back();
  if (!prev.reported || cur.frame != prev.frame + 1) return;
  // a turn's chord points along the mean of both frames' headings (as heading_cost.hpp)
  const Mat3 R_o_w = 0.5 * (cur.T_w_o.topLeftCorner<3, 3>() + prev.T_w_o.topLeftCorner<3, 3>()).transpose();
  track.travel.add_step(R_o_w * (cur.T_w_o.topRightCorner<3, 1>() - prev.T_w_o.topRightCorner<3, 1>()),
                        cur.T_w_o.topLeftCorner<3, 3>().transpose() * up_w_);
}

void ObjectTracker::recenter(int c) {
  // a canonical frame's origin is the box centre, not the points' median
  if (!(options_.recenter_distance_m > 0) || tracks_[c].canonical) return;
  objects::ObjectCluster& cluster = clusters_[c];
  std::vector<Vec3> confirmed;
  for (const objects::ObjectPoint& p : cluster.points)
    if (p.found >= 2) confirmed.push_back(p.X_o);
  if (static_cast<int>(confirmed.size()) < options_.min_inliers) return;
  const Vec3 centre = median_point(confirmed);
  if (centre.norm() <= options_.recenter_distance_m) return;
  // T_w_o' = T_w_o T_o_o' with T_o_o' a translation by centre: the twists of eq. 2 act on the
  // left (T_w_o(i+1) = exp(Pi xi) T_w_o(i)), so they are unchanged
  for (objects::TrackFrame& row : tracks_[c].frames)
    row.T_w_o.topRightCorner<3, 1>() += row.T_w_o.topLeftCorner<3, 3>() * centre;
  for (objects::ObjectPoint& p : cluster.points) p.X_o -= centre;
}

void ObjectTracker::cull(objects::ObjectCluster& cluster) const {
  auto& pts = cluster.points;
  pts.erase(std::remove_if(pts.begin(), pts.end(),
                           [&](const objects::ObjectPoint& p) {
                             return p.visible >= options_.cull_after_visible &&
                                    p.found_ratio() < options_.min_found_ratio;
                           }),
            pts.end());
}

}  // namespace twistslam::tracking
