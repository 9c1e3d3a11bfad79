// The moving objects in the keyframe BA (paper eq. 9, e_dyna and the link): each live
// cluster's poses at the window's keyframes, its points seen from two of them, e_const and its
// LiDAR terms between those poses (e_det, e_reg, the box prior), and the refined values taken
// back. Keyframe observations are kept per point by mark_keyframe.
#include <algorithm>
#include <cmath>
#include <utility>

#include "geometry/se3.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {

void ObjectTracker::mark_keyframe(int frame_index, int max_keyframes) {
  for (size_t c = 0; c < clusters_.size(); ++c) {
    if (!tracks_[c].alive()) continue;
    for (objects::ObjectPoint& p : clusters_[c].points) {
      if (p.last.frame != frame_index) continue;  // not matched (or added) in this frame
      p.keyframe_history.push_back(p.last);
      if (static_cast<int>(p.keyframe_history.size()) > std::max(max_keyframes, 1))
        p.keyframe_history.erase(p.keyframe_history.begin());
    }
  }
}

void ObjectTracker::add_bundle_terms(const std::map<int, int>& slot_of_frame, int max_points,
                                     optim::BAProblem* problem) {
  bundle_links_.clear();
  bundle_observations_.clear();
  for (int c = 0; c < static_cast<int>(clusters_.size()); ++c) {
    const objects::ObjectTrack& track = tracks_[c];
    if (!track.alive()) continue;
    BundleLink link;
    link.cluster = c;
    link.object = static_cast<int>(problem->objects.size());
    optim::BAObject object;
    object.Pi = track.Pi;
    std::map<int, int> pose_of_frame;  // frame -> object pose index
    // the rows before a near re-birth share no point with the later ones (as in the windows)
    const int first =
        track.first_linked_row(options_.reborn_barrier_max_depth_m, options_.reborn_barrier_min_rows);
    for (int r = first; r < static_cast<int>(track.frames.size()); ++r) {
      const objects::TrackFrame& row = track.frames[r];
      const auto slot = slot_of_frame.find(row.frame);
      if (slot == slot_of_frame.end() || !row.reported) continue;
      pose_of_frame[row.frame] = static_cast<int>(object.poses.size());
      object.poses.push_back({slot->second, row.T_w_o, false, row.frame});
      link.rows.push_back(r);
    }
    if (object.poses.size() < 2) continue;  // one pose absorbs its observations: no information
    // the points seen from two of these keyframes, most often found first, at most
    // max_points of them: each object adds poses to the reduced camera system, and its
    // points beyond a few tens add solver time, not information about the cameras
    std::vector<std::pair<int, int>> ranked;  // (-found, point index)
    for (int i = 0; i < static_cast<int>(clusters_[c].points.size()); ++i) {
      int seen = 0;
      for (const auto& o : clusters_[c].points[i].keyframe_history) seen += pose_of_frame.count(o.frame) > 0;
      if (seen >= 2) ranked.emplace_back(-clusters_[c].points[i].found, i);
    }
    std::sort(ranked.begin(), ranked.end());
    if (max_points >= 0 && static_cast<int>(ranked.size()) > max_points) ranked.resize(max_points);
    std::vector<optim::BADynamicObservation> observations;
    std::vector<BundleObservation> sources;
    for (const auto& [found, i] : ranked) {
      const objects::ObjectPoint& p = clusters_[c].points[i];
      const int point = static_cast<int>(object.points_o.size());
      object.points_o.push_back(p.X_o);
      for (const auto& o : p.keyframe_history) {
        const auto pose = pose_of_frame.find(o.frame);
        if (pose == pose_of_frame.end()) continue;
        observations.push_back({link.object, pose->second, point, o.uv, o.u_right, weights_.at(o.octave)});
        sources.push_back({c, i, o.frame});
      }
    }
    if (object.points_o.empty()) continue;
    if (options_.use_const) {  // e_const between the keyframe poses, as in the windows
      object.const_sigma_translation = options_.const_sigma_translation;
      object.const_sigma_rotation = options_.const_sigma_rotation;
    }
    if (lidar_options_.keyframe_ba_terms) add_bundle_lidar_terms(track, link.rows, &object);
    problem->objects.push_back(std::move(object));
    problem->dynamic_observations.insert(problem->dynamic_observations.end(), observations.begin(),
                                         observations.end());
    bundle_observations_.insert(bundle_observations_.end(), sources.begin(), sources.end());
    bundle_links_.push_back(std::move(link));
  }
}

void ObjectTracker::add_bundle_lidar_terms(const objects::ObjectTrack& track,
                                           const std::vector<int>& rows,
                                           optim::BAObject* object) const {
  const ObjectLidarOptions& o = lidar_options_;
  // a row's box in the camera frame it was measured in
  auto T_c_box = [&](const objects::TrackFrame& row) { return row.T_c_w * row.T_w_o_detected; };
  for (size_t k = 0; k < rows.size(); ++k) {
    const objects::TrackFrame& b = track.frames[rows[k]];
    // the box prior, where the object frame is the box frame
    if (o.use_detection_pose && track.canonical && b.has_detection())
      object->boxes.push_back({static_cast<int>(k), T_c_box(b), o.det_pose_sigma_translation,
                               o.det_pose_sigma_rotation, o.huber_det});
    if (k == 0) continue;
    const objects::TrackFrame& a = track.frames[rows[k - 1]];
    // e_det (eq. 5) between the boxes of two keyframes: two boxes' noise, whatever the frames
    // between them
    if (o.use_detection_twist && a.has_detection() && b.has_detection())
      object->motions.push_back({static_cast<int>(k) - 1, static_cast<int>(k),
                                 T_c_box(b) * geometry::se3_inverse(T_c_box(a)),
                                 o.det_sigma_translation, o.det_sigma_rotation, o.huber_det});
    // e_reg (eq. 6-7): the registrations of every frame from a to b, chained; each was put in w
    // with the cameras of its two frames, which cancel along the chain but for the ends'
    if (!o.use_registration) continue;
    Mat4 M_w = Mat4::Identity();
    double var_t = 0, var_r = 0;
    bool chained = true;
    for (int r = rows[k - 1] + 1; r <= rows[k] && chained; ++r) {
      const objects::TrackFrame& row = track.frames[r];
      chained = row.registered;
      M_w = row.M_w_registered * M_w;
      const bool own = row.reg_sigma.minCoeff() > 0;  // from GICP's information
      var_t += std::pow(own ? row.reg_sigma[0] : o.reg_sigma_translation, 2);
      var_r += std::pow(own ? row.reg_sigma[1] : o.reg_sigma_rotation, 2);
    }
    if (chained)
      object->motions.push_back({static_cast<int>(k) - 1, static_cast<int>(k),
                                 b.T_c_w * M_w * geometry::se3_inverse(a.T_c_w), std::sqrt(var_t),
                                 std::sqrt(var_r), o.huber_reg});
  }
}

void ObjectTracker::take_bundle_result(const optim::BAProblem& problem,
                                       const optim::BundleAdjustmentReport& report) {
  // Only the refined cameras come back (the object window of the next frames projects
  // through them). The object poses at the keyframes are not written
  // over the tracked ones: the rows between two keyframes would keep the tracking's poses,
  // and the jumps at the keyframe rows raised the per-frame object RPE (urban seed 0: 0.043
  // -> 0.25 m/m, 0.47 -> 3.4 deg/m, measured); the points stay consistent with those poses.
  for (const BundleLink& link : bundle_links_) {
    const optim::BAObject& object = problem.objects[link.object];
    const objects::ObjectTrack& track = tracks_[link.cluster];
    for (size_t k = 0; k < link.rows.size(); ++k) {
      const auto cam = T_c_w_of_frame_.find(track.frames[link.rows[k]].frame);
      if (cam != T_c_w_of_frame_.end()) cam->second = problem.keyframes[object.poses[k].keyframe].T_c_w;
    }
  }
  // outlier keyframe observations are forgotten (the point itself is judged by its found ratio)
  const size_t n = std::min(bundle_observations_.size(), report.dynamic_outlier.size());
  for (size_t e = 0; e < n; ++e) {
    if (!report.dynamic_outlier[e]) continue;
    const BundleObservation& b = bundle_observations_[e];
    auto& h = clusters_[b.cluster].points[b.point].keyframe_history;
    h.erase(std::remove_if(h.begin(), h.end(), [&](const auto& o) { return o.frame == b.frame; }), h.end());
  }
  bundle_links_.clear();
  bundle_observations_.clear();
}

}  // namespace twistslam::tracking
