// 3D detections in the visual object tracking (paper sec. "Injecting LiDAR scans", eq. 5):
// each frame's boxes are associated one to one with the live clusters (box to cluster within
// detection_max_distance_m, Hungarian); the first box associated with a cluster sets its
// canonical object frame (the box frame), later boxes give its size (per-dimension median)
// and the drift-free twist e_det of the object window (optim/visual_object_window.hpp).
// Not in the paper: a box's LiDAR returns projected into the instance image say on which
// object's mask it lies, and a cluster's first box must lie on the cluster's own.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "geometry/se3.hpp"
#include "objects/assignment.hpp"
#include "objects/association.hpp"
#include "objects/box_axis_rank.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
using detail::contains;
using detail::transform;

namespace {

// Distance from p (camera frame) to the box (0 inside): a cluster's points lie on the
// object's visible faces, up to half a car length from its centre, so the centroid of a car
// seen from behind is ~2 m from the box centre but inside or at the box.
double distance_to_box(const geometry::Box3D& box, const Vec3& p_c) {
  const Mat4 T_c_b = box.pose();
  const Vec3 p_b = T_c_b.topLeftCorner<3, 3>().transpose() * (p_c - T_c_b.topRightCorner<3, 1>());
  const Vec3 half(box.length / 2, box.height / 2, box.width / 2);  // box x, y (down), z
  return (p_b - p_b.cwiseMax(-half).cwiseMin(half)).norm();
}

// Whether p (frame c) lies within margin of a box of the frame other than box d.
bool near_other_box(const std::vector<objects::Detection>& detections, size_t d, const Vec3& p_c,
                    double margin) {
  for (size_t e = 0; e < detections.size(); ++e)
    if (e != d && distance_to_box(detections[e].box, p_c) <= margin) return true;
  return false;
}

}  // namespace

int ObjectTracker::instance_of_box(int d) {
  if (detection_instance_[d] >= 0) return detection_instance_[d];
  int best = 0;
  if (scan_ && !instances_.empty()) {
    const geometry::Box3D& box = detections_[d].box;
    // the object scan's box (grown by the scan margin: a box is as tight as its returns, which
    // scatter across its faces), without the road under it, which every mask's lower edge holds
    const double margin = lidar_options_.scan_margin_m;
    const Points3 returns = detail::points_in_box(*scan_, box.pose(), Mat4::Identity(),
                                                  Vec3(box.length, box.width, box.height), margin,
                                                  lidar_options_.scan_ground_clearance_m);
    std::map<int, int> votes;  // instance -> returns on its mask
    int on_objects = 0;
    for (Eigen::Index i = 0; i < returns.rows(); ++i) {
      const Vec3 p = returns.row(i).transpose();
      // a return in another box's grown box too belongs to either car (a queue's bumpers)
      if (p.z() <= 0.1 || near_other_box(detections_, static_cast<size_t>(d), p, margin)) continue;
      const Vec2 uv = camera_.project(p);
      if (!camera_.in_image(uv)) continue;
      const int instance = instances_.at<int>(static_cast<int>(uv.y()), static_cast<int>(uv.x()));
      const auto cls = instance_class_.find(instance);
      if (instance <= 0 || cls == instance_class_.end() || !contains(options_.object_class_ids, cls->second))
        continue;
      ++votes[instance];
      ++on_objects;
    }
    if (on_objects >= lidar_options_.box_instance_min_returns) {
      int most = 0;
      for (const auto& [instance, n] : votes)
        if (n > most) most = n, best = instance;
    }
  }
  detection_instance_[d] = best;
  return best;
}

std::vector<int> ObjectTracker::associate_detections(const Frame& frame,
                                                     const std::vector<int>& clusters,
                                                     const std::vector<Mat4>& T_w_o,
                                                     const std::vector<int>& instances) {
  std::vector<int> detection_of(clusters.size(), -1);
  if (detections_.empty() || clusters.empty() || !lidar_options_.use_detections) return detection_of;
  const double inf = std::numeric_limits<double>::infinity();
  const double gate = lidar_options_.detection_max_distance_m;
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(clusters.size(), detections_.size(), inf);
  for (size_t i = 0; i < clusters.size(); ++i) {
    const objects::ObjectTrack& track = tracks_[clusters[i]];
    const objects::ObjectCluster& cluster = clusters_[clusters[i]];
    const Mat4 T_c_o = frame.T_c_w * T_w_o[i];
    Vec3 centroid_o = Vec3::Zero();
    if (!track.canonical) {
      if (cluster.points.empty()) continue;
      for (const objects::ObjectPoint& p : cluster.points) centroid_o += p.X_o;
      centroid_o /= static_cast<double>(cluster.points.size());
    }
    const Vec3 centre_c = transform(T_c_o, centroid_o);
    std::vector<int> own_mask_boxes;  // boxes whose returns fall on the cluster's mask
    for (size_t d = 0; d < detections_.size(); ++d) {
      if (detection_used_[d] || detections_[d].class_id != track.class_id) continue;
      const geometry::Box3D& box = detections_[d].box;
      // a canonical track's origin is its box centre; a cluster's centroid lies on its faces
      const double distance = track.canonical ? (centre_c - box.center).norm() : distance_to_box(box, centre_c);
      cost(i, d) = distance;
      // a cluster's first box sets its object frame; the box's LiDAR returns tell on which
      // instance it lies. One on another instance's mask (the nearer car in front of a partly
      // hidden one, whose stereo points straddle both) would move the cluster onto that car
      // and leave its own untracked (crowded seed 4); one on the cluster's own mask is its car
      // even where a far cluster's stereo depth put it beyond the gate
      // (for a canonical track: a vehicle's only; a person's narrow mask catches the returns
      // of whatever stands behind it, crowded seed 0: a ghost 2 m off its pedestrian)
      const bool own_mask_rule = !track.canonical || (lidar_options_.own_mask_boxes_for_canonical &&
                                                      track.link == geometry::LinkType::kPlanar);
      if (!own_mask_rule || instances[i] <= 0 ||
          lidar_options_.box_instance_min_returns <= 0 ||
          !(distance <= lidar_options_.box_instance_max_distance_m))
        continue;
      const int box_instance = instance_of_box(static_cast<int>(d));
      if (box_instance > 0 && box_instance != instances[i]) cost(i, d) = inf;
      if (box_instance == instances[i]) {
        cost(i, d) = std::min(distance, gate);
        own_mask_boxes.push_back(static_cast<int>(d));
      }
    }
    // ... and the only one it may take: a nearer box whose returns were too few to vote is
    // another car's (urban seed 0: a far oncoming car's cluster lay 1.76 m from its own box
    // and 1.70 m from that of a parked car hidden behind it, 9 returns)
    if (!own_mask_boxes.empty())
      for (size_t d = 0; d < detections_.size(); ++d)
        if (!contains(own_mask_boxes, static_cast<int>(d))) cost(i, d) = inf;
  }
  for (const auto& [i, d] : objects::solve_assignment(cost, gate))
    detection_of[i] = d;
  return detection_of;
}

void ObjectTracker::attach_detection(int c, const Frame& frame, int d) {
  objects::ObjectTrack& track = tracks_[c];
  objects::TrackFrame& row = track.last();
  const objects::Detection& det = detections_[d];
  detection_used_[d] = 1;
  const Mat4 T_w_c = geometry::se3_inverse(frame.T_c_w);
  Mat4 T_w_box = T_w_c * det.box.pose();
  // the detector's heading, before it is aligned with the track's (a point extent's is mod pi
  // unless the detector told the car's front)
  const Vec3 detected_heading_w = det.heading_known ? Vec3(T_w_box.block<3, 1>(0, 0)) : Vec3::Zero();
  const Vec3 open_end_w = static_cast<double>(det.open_end) * T_w_box.block<3, 1>(0, 0);  // before any turn
  // a point extent that measured its length: its far end is the one away from the camera
  Vec3 far_end_w = Vec3::Zero();
  if (lidar_options_.point_extent_lengths && det.point_extent && det.open_end == 0) {
    const Vec3 axis_w = T_w_box.block<3, 1>(0, 0);
    const Vec3 camera_to_box_w = T_w_box.topRightCorner<3, 1>() - T_w_c.topRightCorner<3, 1>();
    far_end_w = axis_w.dot(camera_to_box_w) >= 0 ? axis_w : Vec3(-axis_w);
  }
  if (!track.canonical && lidar_options_.canonical_pose) {
    level_cluster_turn(c);
    make_canonical(c, T_w_box);
    track.canonical_frame = row.frame;
  } else {
    // the same box turned by pi is the same object: align it with the track's heading (a
    // non-canonical track's frame has no heading: its previous detection's box has)
    const Mat4* reference = track.canonical ? &row.T_w_o : nullptr;
    for (int r = static_cast<int>(track.frames.size()) - 2; r >= 0 && !reference; --r)
      if (track.frames[r].has_detection()) reference = &track.frames[r].T_w_o_detected;
    const bool across = reference && objects::quarter_turned(T_w_box, *reference);
    const double side_angle = lidar_options_.side_view_min_angle_deg;
    const int rank = across ? objects::axis_rank(det.open_end != 0, T_w_box, T_w_c, side_angle) : 2;
    const bool outranks = across && track.canonical && rank > objects::track_axis_rank(track, side_angle);
    if (across && det.open_end != 0 && !outranks) {
      // a box whose length is the detector's prior, a quarter turn off the track's axis: a
      // partly hidden L-shape read as a car's rear (the detector's 90 deg flips are all such
      // boxes, docs/detection.md). The car is there, but neither its axis nor its centre is:
      // the box keeps the track alive and claims the car, it places nothing.
      row.score = row.confidence = det.score;
      row.range = det.box.center.norm();
      return;
    }
    if (outranks) {
      // a box that knows the axis better than all before it, a quarter turn off the frame they
      // set (a measured length, or a side seen across the view against rear-read boxes: urban
      // s11's car 22, half its side hidden): it decides the axis; the earlier boxes were the
      // quarter-turned ones
      for (objects::TrackFrame& earlier : track.frames) earlier.detection_index = -1;
      make_canonical(c, T_w_box);
      track.canonical_frame = row.frame;
      track.heading_from_motion = false;
    } else if (reference && objects::heading_flipped(T_w_box, *reference)) {
      T_w_box = objects::turned_around(T_w_box);
    }
  }
  row.T_w_o_detected = T_w_box;
  row.detected_heading_w = detected_heading_w;
  row.road_side_heading_w =
      det.heading_known ? Vec3::Zero() : road_side_heading(T_w_c, T_w_box, lidar_options_);
  row.detected_size = Vec3(det.box.length, det.box.width, det.box.height);
  row.open_end_w = open_end_w;
  row.far_end_w = far_end_w;
  row.open_shift_m = 0;
  row.score = det.score;
  row.confidence = det.score;
  row.range = det.box.center.norm();
  row.detection_index = d;  // before the heading check: a turn turns this frame's box too
  if (track.canonical && !track.heading_from_motion) check_heading_from_motion(c);
  if (track.canonical && !track.heading_from_motion) check_heading_from_votes(c);
  track.update_size(lidar_options_.point_extent_length_quantile);
  if (track.canonical_frame != row.frame) refine_canonical(c);
}

int ObjectTracker::free_instance_under(const geometry::Box3D& box) const {
  if (instances_.empty()) return -1;
  const Vec3 centre_c = box.center;
  if (centre_c.z() <= 0.1) return -1;
  const Vec2 uv = camera_.project(centre_c);
  if (!camera_.in_image(uv)) return -1;
  const int instance = instances_.at<int>(static_cast<int>(uv.y()), static_cast<int>(uv.x()));
  const auto cls = instance_class_.find(instance);
  if (instance <= 0 || assigned_instances_.count(instance) || cls == instance_class_.end() ||
      !contains(options_.object_class_ids, cls->second))
    return -1;
  return instance;
}

void ObjectTracker::attach_new_cluster_detections(const Frame& frame, int first_new) {
  std::vector<int> fresh, instances;
  std::vector<Mat4> poses;
  for (int c = first_new; c < static_cast<int>(tracks_.size()); ++c) {
    fresh.push_back(c);
    poses.push_back(tracks_[c].last().T_w_o);
    instances.push_back(clusters_[c].instance);
  }
  const std::vector<int> detection_of = associate_detections(frame, fresh, poses, instances);
  for (size_t i = 0; i < fresh.size(); ++i)
    if (detection_of[i] >= 0) {
      attach_detection(fresh[i], frame, detection_of[i]);
      register_scan(fresh[i], frame);  // its first object scan
      backfill_from_boxes(fresh[i]);
    }
}

}  // namespace twistslam::tracking
