// The life cycle of an object cluster (paper sec. "Clusters creation"): new clusters from
// instance masks (at the ground-contact depth or the nearest stereo depth where stereo fails),
// points joining and being culled or retired, re-seeding after a failure, the travel
// direction, and re-centring of the object frame. Search and twist estimation are in
// object_tracker.cpp, the windows (sliding and final smoothing) in object_windows.cpp.
#include <algorithm>
#include <cmath>
#include <iterator>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "tracking/ground_contact.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"
#include "tracking/stereo_depth_fill.hpp"

namespace twistslam::tracking {

using detail::contains;
using detail::median_point;
using detail::median_value;
using detail::observe;
using detail::recenter_points;
using detail::transform;

namespace {
// the spread recenter_max_spread_m bounds: between the 10 % and 90 % quantiles, so that a
// few wrong points at either end do not count
constexpr double kRecenterSpreadQuantile = 0.1;
}  // namespace

std::vector<std::pair<int, Vec3>> ObjectTracker::free_instance_points(const Frame& frame,
                                                                      int instance) const {
  std::vector<std::pair<int, Vec3>> out;
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  const map::StereoKeypoints& k = frame.keypoints;
  const double tolerance = lidar_options_.instance_lidar_max_depth_error;
  for (int i = 0; i < static_cast<int>(k.size()); ++i) {
    if (instance_of_keypoint_[i] != instance || claimed_by_[i] >= 0 || !k.has_depth(i) ||
        k.depth[i] > options_.max_depth_m)
      continue;
    if (tolerance > 0) {
      // off the surface the LiDAR sees there: a match on a nearer car's edge, or a wrong one
      const double lidar_depth = instance_lidar_depth_near(instance, k.uv[i]);
      if (std::abs(k.depth[i] - lidar_depth) > tolerance * lidar_depth) continue;  // NaN: kept
    }
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
                           options_.min_contact_fraction, options_.max_depth_m, 2,
                           options_.contact_depth_quantile, options_.contact_height_m);
  if (!contact.valid) return out;
  const map::StereoKeypoints& k = frame.keypoints;
  for (int i : free_mono_keypoints(frame, instance))
    out.emplace_back(i, transform(T_w_c, camera_.backproject(k.uv[i], contact.depth)));
  return out;
}

std::vector<int> ObjectTracker::free_mono_keypoints(const Frame& frame, int instance) const {
  std::vector<int> out;
  const map::StereoKeypoints& k = frame.keypoints;
  for (int i = 0; i < static_cast<int>(k.size()); ++i)
    if (instance_of_keypoint_[i] == instance && claimed_by_[i] < 0 && !k.has_depth(i)) out.push_back(i);
  return out;
}

std::vector<std::pair<int, Vec3>> ObjectTracker::depth_fill_points(
    const Frame& frame, int instance, const std::vector<std::pair<int, Vec3>>& stereo) const {
  const map::StereoKeypoints& k = frame.keypoints;
  std::vector<Vec2> stereo_uv, mono_uv;
  std::vector<double> stereo_depth;
  for (const auto& s : stereo) stereo_uv.push_back(k.uv[s.first]), stereo_depth.push_back(k.depth[s.first]);
  const std::vector<int> mono = free_mono_keypoints(frame, instance);
  for (int i : mono) mono_uv.push_back(k.uv[i]);
  const std::vector<double> depth = nearest_stereo_depths(
      stereo_uv, stereo_depth, mono_uv,
      {options_.depth_fill_min_points, options_.depth_fill_max_depth_m,
       options_.depth_fill_min_stereo_share});
  std::vector<std::pair<int, Vec3>> out;
  if (depth.empty()) return out;
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  for (size_t m = 0; m < mono.size(); ++m)
    if (std::isfinite(depth[m]))
      out.emplace_back(mono[m], transform(T_w_c, camera_.backproject(k.uv[mono[m]], depth[m])));
  return out;
}

bool ObjectTracker::seed_points(const Frame& frame, int instance, int min_points,
                                bool ground_contact, std::vector<std::pair<int, Vec3>>* kept,
                                Vec3* centroid, bool* lidar_seeded_out,
                                bool* contact_seeded_out) const {
  auto fresh = free_instance_points(frame, instance);
  const double ratio = lidar_options_.mask_max_depth_ratio;
  const std::vector<double>* returns = ratio > 0 ? mask_lidar_depths(instance) : nullptr;
  if (returns && static_cast<int>(returns->size()) >= lidar_options_.mask_min_returns) {
    // a stereo point that far in front of the surface the LiDAR sees on the mask cannot be on
    // it: a wrong match. Crowded s4, classical detector: 7 stereo depths at 1.5-1.6 m (SAD
    // matches at the search's near end) on a mask whose car was 8 m away seeded a ghost 1-2 m
    // before the camera. Points beyond the surface are kept (a mask's returns can be its
    // nearer parts). Placing the near ones at the LiDAR depth instead cost urban s0 a car
    // (classical detector, 6/6 -> 5/6) and crowded s1 RPE_r (0.173 -> 0.204 deg/m)
    const double mask_depth = median_value(*returns);
    const map::StereoKeypoints& k = frame.keypoints;
    fresh.erase(std::remove_if(fresh.begin(), fresh.end(),
                               [&](const std::pair<int, Vec3>& f) { return mask_depth > ratio * k.depth[f.first]; }),
                fresh.end());
  }
  const size_t num_stereo = fresh.size();
  // keypoints whose depth the scan gave (keypoint_lidar_depth) seed as the LiDAR completion does
  size_t num_image_stereo = 0;
  for (const auto& f : fresh)
    num_image_stereo += f.first >= static_cast<int>(keypoint_lidar_filled_.size()) || !keypoint_lidar_filled_[f.first];
  const bool filled_seed = static_cast<int>(num_image_stereo) < min_points && num_image_stereo < num_stereo;
  bool lidar_seeded = false;
  if (static_cast<int>(num_stereo) < min_points && ground_contact && lidar_options_.instance_lidar_depth) {
    // the LiDAR's depth where stereo failed, for vehicles (a person's mask lets returns of the
    // background through: urban s4's pedestrian 132 became a 3.7 m long ghost); used only when
    // it completes the seed, else the image-only cues below place the same keypoints
    const auto lidar = lidar_depth_points(frame, instance);
    if (static_cast<int>(num_stereo + lidar.size()) >= min_points) {
      fresh.insert(fresh.end(), lidar.begin(), lidar.end());
      lidar_seeded = true;
    }
  }
  if (lidar_seeded_out) *lidar_seeded_out = lidar_seeded || filled_seed;
  if (!lidar_seeded && static_cast<int>(fresh.size()) < min_points && ground_contact && options_.ground_contact &&
      !labels_.empty() && road_plane_w_.head<3>().norm() > 0) {
    const auto mono = ground_contact_points(frame, instance);
    // the stereo points keep their depth: they place the car where they can
    fresh.insert(fresh.end(), mono.begin(), mono.end());
    if (contact_seeded_out) *contact_seeded_out = !mono.empty();
    // the contact gives the depth the points lack: fewer of them carry the planar twist
    if (!mono.empty()) min_points = std::min(min_points, options_.min_contact_cluster_points);
  }
  if (!lidar_seeded && ground_contact && fresh.size() == num_stereo &&
      static_cast<int>(num_stereo) < depth_fill_below_points_) {
    const auto mono = depth_fill_points(frame, instance, fresh);
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
  p.X_o = p.X_o_placed = X_o;
  p.descriptor = frame.keypoints.descriptors[k];
  observe(p, {frame.index, frame.keypoints.uv[k], frame.keypoints.u_right[k], frame.keypoints.octave[k]},
          options_.window_frames, options_.final_smoothing);
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

bool ObjectTracker::reseed(int c, const Frame& frame, int instance, Mat4* T_w_o,
                           bool* contact_seeded, bool* reborn_out) {
  std::vector<std::pair<int, Vec3>> kept;
  Vec3 centroid;
  const bool vehicle = tracks_[c].link == geometry::LinkType::kPlanar;
  if (contact_seeded) *contact_seeded = false;
  if (!seed_points(frame, instance, min_seed_points(tracks_[c].link), vehicle, &kept, &centroid,
                   nullptr, contact_seeded))
    return false;
  objects::ObjectCluster& cluster = clusters_[c];
  // A cluster without a velocity yet (it failed in its second frame) has no prediction worth
  // keeping: its origin moves to the new points' centroid, as a new cluster's would, and its
  // one-frame-old points go. Nor has one whose velocity is a single twist that then failed
  // and whose new points lie away from where its old ones are predicted: a far car's first
  // twist can take its birth points' depth error for motion (urban s28's parked car at 37 m:
  // born 5.5 m deep, its first twist 3 m a frame towards the camera, and each re-seed at the
  // prediction carried that on), so it is re-born too. An older cluster keeps its points at
  // the predicted pose: they hold its extent (the box until detections give sizes), and the
  // unmatched ones are culled.
  objects::ObjectTrack& track = tracks_[c];
  const bool has_velocity = !cluster.velocity.isZero();
  bool reborn = !has_velocity;
  // near, a stereo depth is good to centimetres and the twist with it; the medians of a near
  // car's parts differ by metres where a view cuts it (real KITTI 0001's car 0 at 4-6 m,
  // leaving the image: re-born, its rows ran 1 m off and it was lost)
  const double depth = (frame.T_c_w * *T_w_o)(2, 3);
  if (has_velocity && track.hits - 1 < options_.reseed_trusted_velocity_twists &&
      depth >= options_.reseed_reborn_min_depth_m) {
    std::vector<Vec3> old_w, new_w;
    for (const auto& p : cluster.points) old_w.push_back(transform(*T_w_o, p.X_o));
    for (const auto& f : kept) new_w.push_back(f.second);
    reborn = old_w.empty() ||
             (median_point(old_w) - median_point(new_w)).norm() > options_.reseed_reborn_min_offset_m;
  }
  if (reborn_out) *reborn_out = reborn && !track.canonical;
  if (reborn && !track.canonical) {  // a canonical origin is its box's
    // (seen in one or two frames, they are not retired for the final smoothing either)
    T_w_o->topRightCorner<3, 1>() = centroid;
    cluster.points.clear();
    cluster.retired.clear();
    cluster.velocity.setZero();
    track.hits = std::min(track.hits, 1);  // never tracked again: its re-seeds' reporting rules
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
  bool lidar_seeded = false;
  if (!seed_points(frame, instance, min_seed_points(link), planar, &kept, &centroid, &lidar_seeded))
    return false;

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
  // a cluster the LiDAR completed is reported once tracked: on real KITTI 0001 such births on
  // masks of false boxes made one-frame tracks (camera alone: 2 false rows where there were 0)
  row.reported = !lidar_seeded;
  row.T_c_w = frame.T_c_w;
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
  const objects::TrackFrame& last = tracks_[c].frames.back();
  const bool far = transform(last.T_c_w * last.T_w_o, Vec3::Zero()).z() > options_.recenter_spread_min_depth_m;
  // the points the track confirmed and later culled (kept for the final smoothing) still say
  // where its earlier rows saw the car: with them the median converges instead of following
  // whichever points are live now. A far car seeded at its ground contact holds mono points
  // at a guessed depth (metres off at 45 m), and the stereo points it gains later disagree
  // with them: the median of all lies between, their spread bars the re-centring, and the
  // origin stays off the car. Near, the stereo holds most points and the guessed ones fill
  // the faces it misses (recenter_on_stereo_points there lost crowded s1's car 17).
  const std::vector<Vec3> confirmed =
      recenter_points(cluster, options_.recenter_with_retired_points,
                      options_.recenter_on_stereo_points && far, options_.min_inliers);
  if (static_cast<int>(confirmed.size()) < options_.min_inliers) return;
  const Vec3 centre = median_point(confirmed);
  if (centre.norm() <= options_.recenter_distance_m) return;
  // a far cluster's points spread wider than a car is long disagree about where it is (a far
  // track whose depth motion lagged placed its later points metres ahead of its origin): their
  // median is no centre, and moving every row onto it would move the rows they never saw too
  if (options_.recenter_max_spread_m > 0 && far &&
      detail::largest_quantile_spread(confirmed, kRecenterSpreadQuantile) > options_.recenter_max_spread_m)
    return;
  // a cluster whose points are nearly all placed without a disparity (a car seen through a
  // gap between nearer ones, which the right camera does not see: its points at the ground
  // contact or their few stereo neighbours' depth) holds guessed depths that scatter by
  // metres and drift in the windows; their median jumps between depth groups from frame to
  // frame (crowded s6's queued car 15: moves of 1-4 m, the track 5 m short of the car), so the
  // origin stays where the cluster was seeded
  const double min_stereo = options_.recenter_min_stereo_fraction;
  if (min_stereo > 0 &&
      detail::confirmed_stereo_fraction(cluster, options_.recenter_with_retired_points) <= min_stereo)
    return;
  // T_w_o' = T_w_o T_o_o' with T_o_o' a translation by centre: the twists of eq. 2 act on the
  // left (T_w_o(i+1) = exp(Pi xi) T_w_o(i)), so they are unchanged
  for (objects::TrackFrame& row : tracks_[c].frames)
    row.T_w_o.topRightCorner<3, 1>() += row.T_w_o.topLeftCorner<3, 3>() * centre;
  for (objects::ObjectPoint& p : cluster.points) p.X_o -= centre, p.X_o_placed -= centre;
  for (objects::ObjectPoint& p : cluster.retired) p.X_o -= centre, p.X_o_placed -= centre;
}

void ObjectTracker::cull(objects::ObjectCluster& cluster) const {
  auto& pts = cluster.points;
  const auto keep_end = std::stable_partition(pts.begin(), pts.end(), [&](const objects::ObjectPoint& p) {
    return !(p.visible >= options_.cull_after_visible && p.found_ratio() < options_.min_found_ratio);
  });
  std::vector<objects::ObjectPoint> culled(std::make_move_iterator(keep_end),
                                           std::make_move_iterator(pts.end()));
  pts.erase(keep_end, pts.end());
  retire(cluster, std::move(culled));
}

void ObjectTracker::retire(objects::ObjectCluster& cluster, std::vector<objects::ObjectPoint>&& points) const {
  if (!options_.final_smoothing) return;
  for (objects::ObjectPoint& p : points) {
    if (p.archive.size() < 2) continue;  // one observation fixes neither point nor pose
    p.history.clear();
    p.history.shrink_to_fit();
    p.keyframe_history.clear();
    p.keyframe_history.shrink_to_fit();
    cluster.retired.push_back(std::move(p));
  }
}

}  // namespace twistslam::tracking
