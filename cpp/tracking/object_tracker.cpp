#include "tracking/object_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <unordered_set>

#include "geometry/link_projection.hpp"
#include "geometry/se3.hpp"
#include "objects/association.hpp"
#include "objects/instance_association.hpp"
#include "objects/motion_model.hpp"
#include "tracking/instance_pixels.hpp"
#include "tracking/object_keypoints.hpp"
#include "tracking/object_point_helpers.hpp"

namespace twistslam::tracking {
namespace {

using detail::contains;
using detail::observe;
using detail::transform;

}  // namespace

ObjectTracker::ObjectTracker(const geometry::StereoCamera& camera,
                             const ObjectTrackingOptions& options,
                             const std::vector<float>& scale_factors, LevelWeights weights,
                             const ObjectLidarOptions& lidar_options)
    : camera_(camera), options_(options), lidar_options_(lidar_options),
      scale_factors_(scale_factors), weights_(std::move(weights)),
      search_(object_stereo_search(options)) {
  lm_options_.max_iterations = options.lm_iterations;
  lm_options_.min_inliers = options.min_inliers;
}

void ObjectTracker::reset() {
  tracks_.clear();
  clusters_.clear();
  T_c_w_of_frame_.clear();
  last_scan_.clear();
  next_id_ = 0;
  last_frame_ = -1;
  previous_gray_left_.release();
  previous_gray_frame_ = -1;
  previous_lk_pyramid_.clear();
  previous_lk_frame_ = -1;
}

bool ObjectTracker::update_cluster(int c, const Frame& frame, std::vector<Match> matches,
                                   int instance, const Mat4& T_w_o_pred, int detection) {
  objects::ObjectCluster& cluster = clusters_[c];
  objects::ObjectTrack& track = tracks_[c];
  const Mat4 T_w_o_prev = track.last().T_w_o;
  matches.erase(std::remove_if(matches.begin(), matches.end(),
                               [&](const Match& m) { return !keypoint_allowed(m.keypoint, instance); }),
                matches.end());
  // observations: the keypoint matches, then (few matches) the flow-located points
  const double depth_pred = (frame.T_c_w * T_w_o_pred)(2, 3);
  std::vector<FlowObservation> flow_obs = flow_observations(cluster, matches, instance, depth_pred, track.canonical);
  size_t estimated_matches = 0;  // est.inlier: these matches, then estimated_flow
  std::vector<FlowObservation> estimated_flow;
  auto estimate = [&](const Vec6& xi_init) {
    estimated_matches = matches.size();
    estimated_flow = flow_obs;
    std::vector<objects::TwistObservation> obs;
    obs.reserve(matches.size() + flow_obs.size());
    for (const Match& m : matches) obs.push_back(observation(cluster.points[m.point], frame, m.keypoint));
    for (const FlowObservation& f : flow_obs) {
      objects::TwistObservation o;
      o.X_o = cluster.points[f.point].X_o;
      o.uv = f.uv;
      o.u_right = f.u_right;
      o.inv_sigma2 = weights_.at(cluster.points[f.point].last.octave);
      obs.push_back(o);
    }
    return objects::estimate_object_twist(camera_, frame.T_c_w, T_w_o_prev, track.Pi, obs,
                                          xi_init, lm_options_);
  };
  auto enough = [&] { return static_cast<int>(matches.size() + flow_obs.size()) >= options_.min_inliers; };
  objects::TwistEstimate est;
  if (enough()) est = estimate(track.Pi * cluster.velocity);
  // second pass (eq. 4): project every point with the new pose, re-match, optimise again
  const Mat4 T_w_o_first = est.valid ? est.T_w_o : T_w_o_pred;
  const size_t before = matches.size();
  refine_matches(cluster, frame.T_c_w * T_w_o_first, frame, instance, &matches);
  if (matches.size() > before) {
    flow_obs = flow_observations(cluster, matches, instance, depth_pred, track.canonical);
    if (enough()) est = estimate(est.valid ? est.xi : Vec6(track.Pi * cluster.velocity));
  }
  const bool valid = est.valid && est.num_inliers >= options_.min_inliers &&
                     (est.T_w_o.topRightCorner<3, 1>() - T_w_o_prev.topRightCorner<3, 1>()).norm() <=
                         options_.max_step_m;
  // Lost its points while its instance is still associated: new points from the instance,
  // same track. Otherwise the instance stays claimed by a failing cluster until it dies
  // (max_misses frames) and only then starts a new track: a gap and a fragmented track.
  Mat4 T_w_o_reseed = T_w_o_pred;
  int reseed_instance = instance;
  // a canonical track its box keeps alive: without an associated instance, the one under the
  // box is its own (a new cluster started on it would duplicate the object)
  const bool box_kept = !valid && detection >= 0 && track.canonical;
  if (box_kept && reseed_instance < 0) reseed_instance = free_instance_under(detections_[detection].box);
  bool contact_seeded = false, reborn = false;
  const bool reseeded = !valid && reseed_instance >= 0 && options_.reseed_after_misses > 0 &&
                        track.misses + 1 >= options_.reseed_after_misses &&
                        reseed(c, frame, reseed_instance, &T_w_o_reseed, &contact_seeded, &reborn);
  if (reseeded && reseed_instance != instance) {
    assigned_instances_.insert(reseed_instance);
    instance = reseed_instance;
  }

  objects::TrackFrame row;
  row.frame = frame.index;
  if (reseeded) {
    row.T_w_o = T_w_o_reseed;
    track.last().xi = track.Pi * geometry::twist_between(T_w_o_prev, T_w_o_reseed);
    track.misses = 0;
    row.detected = false;
    row.reborn = reborn;
  } else if (valid) {
    row.T_w_o = est.T_w_o;
    track.last().xi = est.xi;  // eq. 2: T_w_o(i+1) = exp(Pi xi_i) T_w_o(i)
    cluster.velocity = est.xi;
    row.detected = true;
    ++track.hits;
    track.misses = 0;
    track.state = objects::TrackState::kConfirmed;
    if (track.confirmed_frame < 0) track.confirmed_frame = frame.index;
  } else if (box_kept) {
    // no twist, but a box: the track lives on from its prediction, which the window then
    // pulls towards the box (e_det, the pose prior) under e_const: a box alone is a noisy pose
    row.T_w_o = T_w_o_pred;
    track.last().xi = track.Pi * cluster.velocity;
    track.misses = 0;
    track.state = objects::TrackState::kConfirmed;
  } else {
    row.T_w_o = T_w_o_pred;
    track.last().xi = track.Pi * cluster.velocity;
    ++track.misses;
    track.state = track.misses > options_.max_misses ? objects::TrackState::kDead
                                                      : objects::TrackState::kLost;
  }
  // a cluster never tracked since its birth, re-seeded: the row is one frame's stereo points,
  // reported only where their depth is good to a car's half length; placed by its ground
  // contact (8-15 % beyond the car's near face), nearer still
  const bool never_tracked = track.hits < 2;
  const double report_max_depth = contact_seeded ? options_.untracked_contact_report_max_depth_m
                                                 : options_.untracked_report_max_depth_m;
  bool consistent = true;
  if (never_tracked && reseeded && options_.untracked_reseed_max_jump_m > 0) {
    const objects::TrackFrame& previous = track.last();
    const int apart = std::max(1, frame.index - previous.frame);
    consistent = (row.T_w_o.topRightCorner<3, 1>() - previous.T_w_o.topRightCorner<3, 1>()).norm() <=
                 options_.untracked_reseed_max_jump_m * apart;
  }
  const bool reseed_reported =
      reseeded && consistent &&
      (!never_tracked || (frame.T_c_w * row.T_w_o)(2, 3) <= report_max_depth);
  row.reported = valid || reseed_reported || box_kept;
  row.T_c_w = frame.T_c_w;
  track.frames.push_back(row);
  if (detection >= 0) attach_detection(c, frame, detection);
  if (reseeded) return false;  // fresh points: no statistics, window or new points this frame

  // point statistics: visible where predicted inside the image, found where an inlier
  const Mat4 T_c_o = frame.T_c_w * row.T_w_o;
  for (objects::ObjectPoint& p : cluster.points) {
    const Vec3 X_c = transform(T_c_o, p.X_o);
    if (X_c.z() > 0.1 && camera_.in_image(camera_.project(X_c))) ++p.visible;
  }
  if (valid) {
    for (size_t j = 0; j < estimated_matches; ++j) {
      if (!est.inlier[j]) continue;
      const Match& m = matches[j];
      objects::ObjectPoint& p = cluster.points[m.point];
      observe(p, {frame.index, frame.keypoints.uv[m.keypoint], frame.keypoints.u_right[m.keypoint],
                  frame.keypoints.octave[m.keypoint]}, options_.window_frames,
              options_.final_smoothing);
      p.descriptor = frame.keypoints.descriptors[m.keypoint];
      p.class_votes.add(frame.keypoints.label[m.keypoint]);
      ++p.found;
      claimed_by_[m.keypoint] = c;
    }
    // a flow-located point keeps its chain (the next frame's flow starts at this pixel)
    for (size_t j = 0; j < estimated_flow.size(); ++j) {
      if (!est.inlier[estimated_matches + j]) continue;
      objects::ObjectPoint& p = cluster.points[estimated_flow[j].point];
      observe(p, {frame.index, estimated_flow[j].uv, estimated_flow[j].u_right, p.last.octave},
              options_.window_frames,
              options_.final_smoothing);
      ++p.found;
    }
  }
  if (valid || box_kept) register_scan(c, frame);
  if ((valid || box_kept) && options_.window_frames >= 3) refine_window(c);
  if (valid) recenter(c);
  if (valid) add_travel_step(track);
  if (instance >= 0) {
    cluster.instance = instance;
    const auto cls = instance_class_.find(instance);
    if (cls != instance_class_.end()) cluster.class_votes.add(cls->second);
    // only with a valid pose: points placed with a stale prediction would duplicate the
    // cluster's own points a motion step away
    if (valid) add_points(c, frame, instance);
  }
  cull(cluster);
  return valid;
}

ObjectTrackingReport ObjectTracker::track(const Frame& input_frame, const cv::Mat& instances,
                                          const cv::Mat& flow, const Vec3& up_w,
                                          const cv::Mat& labels, const Vec4& road_plane_w,
                                          const std::vector<objects::Detection>& detections,
                                          const Points3* scan, const cv::Mat& gray_left,
                                          const cv::Mat& gray_right) {
  ObjectTrackingReport report;
  if (!options_.enabled) return report;
  if (!instances.empty() && (instances.type() != CV_32SC1 || instances.cols != camera_.width ||
                             instances.rows != camera_.height))
    throw std::invalid_argument("instances: expected int32 instance ids of the image size");
  if (!flow.empty() && (flow.type() != CV_32FC2 || flow.cols != camera_.width ||
                        flow.rows != camera_.height))
    throw std::invalid_argument("flow: expected float32 (u, v) per pixel of the image size");
  if (!labels.empty() && (labels.type() != CV_32SC1 || labels.cols != camera_.width ||
                          labels.rows != camera_.height))
    throw std::invalid_argument("labels: expected int32 class ids of the image size");

  T_c_w_of_frame_[input_frame.index] = input_frame.T_c_w;
  scan_ = scan && scan->rows() > 0 ? scan : nullptr;
  mask_lidar_depths_.clear();
  mask_lidar_points_.clear();
  instance_returns_.clear();
  mask_lidar_depths_ready_ = false;
  up_w_ = up_w;
  instances_ = instances;
  labels_ = labels;
  flow_ = flow;
  const bool pair = !gray_left.empty() && !gray_right.empty();
  if (pair && (gray_left.type() != CV_8UC1 || gray_right.type() != CV_8UC1 ||
               gray_left.cols != camera_.width || gray_left.rows != camera_.height ||
               gray_right.size() != gray_left.size()))
    throw std::invalid_argument("gray_left / gray_right: expected 8-bit gray images of the image size");
  gray_left_ = pair ? gray_left : cv::Mat();
  gray_right_ = pair ? gray_right : cv::Mat();
  road_plane_w_ = road_plane_w;
  while (static_cast<int>(T_c_w_of_frame_.size()) > std::max(options_.window_frames, 2) + 1)
    T_c_w_of_frame_.erase(T_c_w_of_frame_.begin());
  const size_t n = input_frame.keypoints.size();
  instance_of_keypoint_.assign(n, 0);
  // with 3D boxes a box places its car: the border rule is the LiDAR fusion's own
  const bool boxed = lidar_options_.use_detections && !detections.empty();
  const double border_px = boxed ? lidar_options_.instance_border_px : options_.instance_border_px;
  instance_border_px_ = border_px;
  depth_fill_below_points_ =
      boxed ? lidar_options_.depth_fill_below_points : options_.depth_fill_below_points;
  if (!instances.empty())
    for (size_t i = 0; i < n; ++i) {
      const double scale = level_scale(i < input_frame.keypoints.octave.size() ? input_frame.keypoints.octave[i] : 0);
      instance_of_keypoint_[i] = instance_at_keypoint(instances, input_frame.keypoints.uv[i],
                                                      border_px * scale);
    }
  claimed_by_.assign(n, -1);
  assigned_instances_.clear();
  std::map<int, objects::LabelVotes> votes;  // instance -> classes of its keypoints
  for (size_t i = 0; i < n; ++i)
    if (instance_of_keypoint_[i] > 0) votes[instance_of_keypoint_[i]].add(input_frame.keypoints.label[i]);
  instance_class_.clear();
  for (const auto& [instance, v] : votes) instance_class_[instance] = v.best();

  // the road plane is re-estimated as the map grows: the planar links follow its normal
  for (objects::ObjectTrack& t : tracks_)
    if (t.alive() && t.link == geometry::LinkType::kPlanar) t.Pi = geometry::projector_planar(up_w);
  // vehicle keypoints without a good stereo depth take their mask's LiDAR depth
  Frame lidar_frame;
  const Frame& frame = with_instance_lidar_depth(input_frame, &lidar_frame);
  // 1. search every live cluster from its prediction
  std::vector<int> live;
  std::vector<Mat4> predicted;
  std::vector<std::vector<Match>> matches;
  std::vector<objects::ClusterInstanceEvidence> evidence;
  for (int c = 0; c < static_cast<int>(tracks_.size()); ++c) {
    if (!tracks_[c].alive()) continue;
    live.push_back(c);
    predicted.push_back(objects::predict_pose(tracks_[c].last().T_w_o, clusters_[c].velocity, tracks_[c].Pi));
    evidence.emplace_back();
    matches.push_back(search_cluster(clusters_[c], frame.T_c_w * predicted.back(), frame,
                                     instances, flow, &evidence.back()));
  }
  // 2. instances <-> clusters
  objects::InstanceAssociationOptions assoc{options_.min_shared_points, options_.min_mask_overlap};
  std::vector<int> instance_of = objects::associate_instances(evidence, assoc);
  release_occluding_instances(live, predicted, frame, evidence, &instance_of);
  for (int inst : instance_of)
    if (inst > 0) assigned_instances_.insert(inst);
  // 3. twists, largest clusters first (they claim contested keypoints)
  std::vector<int> order(live.size());
  for (size_t j = 0; j < order.size(); ++j) order[j] = static_cast<int>(j);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return clusters_[live[a]].points.size() > clusters_[live[b]].points.size();
  });
  // 3D detections <-> clusters, at their predicted poses (LiDAR fusion)
  detections_.clear();
  for (const objects::Detection& d : detections)
    if (d.score >= lidar_options_.detection_min_score && d.box.valid()) detections_.push_back(d);
  detection_used_.assign(detections_.size(), 0);
  detection_instance_.assign(detections_.size(), -1);
  const std::vector<int> detection_of = associate_detections(frame, live, predicted, instance_of);
  for (int j : order) {
    const bool valid = update_cluster(live[j], frame, std::move(matches[j]), instance_of[j],
                                      predicted[j], detection_of[j]);
    ++(valid ? report.num_tracked : report.num_missed);
  }
  // 4. new clusters from the instances of object classes nobody claimed
  const int first_new = static_cast<int>(tracks_.size());
  if (!instances.empty()) {
    for (const auto& [instance, class_id] : instance_class_) {
      if (assigned_instances_.count(instance) || !contains(options_.object_class_ids, class_id)) continue;
      report.num_new += start_cluster(frame, instance, class_id, up_w);
    }
  }
  attach_new_cluster_detections(frame, first_new);
  hide_duplicate_tracks(frame);
  hide_see_through_tracks(frame);
  hide_lidar_contradicted_tracks(frame);
  keep_far_lidar_returns(frame);
  remember_unused_boxes(frame);
  for (int c = 0; c < static_cast<int>(tracks_.size()); ++c)
    if (tracks_[c].alive()) tracks_[c].class_id = clusters_[c].class_votes.best(tracks_[c].class_id);
  hide_far_small_tracks(frame);  // after the class votes: this frame's class
  for (int owner : claimed_by_) report.num_points += owner >= 0;
  last_frame_ = frame.index;
  if (options_.flow_observations_lk_max_px > 0 && !gray_left_.empty()) {
    gray_left_.copyTo(previous_gray_left_);
    previous_gray_frame_ = frame.index;
  }
  // kept for the next frame unless its first level is a view of the caller's image
  const bool keep_pyramid = !lk_pyramids_.empty() && previous_gray_frame_ == frame.index &&
                            lk_pyramids_.current[0].datastart != gray_left_.datastart;
  previous_lk_pyramid_ = keep_pyramid ? std::move(lk_pyramids_.current) : std::vector<cv::Mat>();
  previous_lk_frame_ = keep_pyramid ? frame.index : -1;
  lk_pyramids_ = LkPyramids();
  // the caller's images are this call's only: no view of them outlives it
  gray_left_.release();
  gray_right_.release();
  instances_.release();
  labels_.release();
  flow_.release();
  detections_.clear();
  scan_ = nullptr;
  mask_lidar_depths_.clear();
  mask_lidar_points_.clear();
  instance_returns_.clear();
  mask_lidar_depths_ready_ = false;
  drop_stale_scans(frame.index);
  return report;
}

}  // namespace twistslam::tracking
