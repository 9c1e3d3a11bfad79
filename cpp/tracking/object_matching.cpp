// Object keypoint matching (paper eq. 4's data): each cluster point searched around its
// flow-predicted pixel (or its projection), then, once the twist is known, the unmatched
// points projected and matched again; the observations the twist LM takes from them.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "tracking/instance_pixels.hpp"
#include "tracking/object_point_helpers.hpp"
#include "tracking/object_tracker.hpp"

namespace twistslam::tracking {
namespace {

using detail::transform;

// Search window scale for a cluster without a velocity (its first frames): 3 x 12 px covers a
// car crossing the image at 15 m and 18 km/h relative speed between two frames.
constexpr double kNewbornSearchScale = 3.0;

}  // namespace

double ObjectTracker::level_scale(int octave) const {
  if (scale_factors_.empty()) return 1.0;
  return scale_factors_[std::clamp(octave, 0, static_cast<int>(scale_factors_.size()) - 1)];
}

objects::TwistObservation ObjectTracker::observation(const objects::ObjectPoint& p,
                                                     const Frame& frame, int k) const {
  objects::TwistObservation o;
  o.X_o = p.X_o;
  o.uv = frame.keypoints.uv[k];
  o.u_right = frame.keypoints.u_right[k];
  o.inv_sigma2 = weights_.at(frame.keypoints.octave[k]);
  return o;
}

std::vector<ObjectTracker::Match> ObjectTracker::search_cluster(
    const objects::ObjectCluster& cluster, const Mat4& T_c_o, const Frame& frame,
    const cv::Mat& instances, const cv::Mat& flow,
    objects::ClusterInstanceEvidence* evidence) const {
  std::vector<Match> matches;
  std::vector<int> candidates;
  const bool newborn = cluster.velocity.isZero();
  for (int i = 0; i < static_cast<int>(cluster.points.size()); ++i) {
    const objects::ObjectPoint& p = cluster.points[i];
    const Vec3 X_c = transform(T_c_o, p.X_o);
    const bool in_front = X_c.z() > 0.1;
    const Vec2 projected = in_front ? camera_.project(X_c) : Vec2(-1e9, -1e9);
    if (in_front && camera_.in_image(projected)) {
      ++evidence->num_projected;
      if (!instances.empty()) evidence->projected.add(pixel_value(instances, projected));
    }
    Vec2 predicted;
    double radius;
    const bool by_flow = p.last.frame == last_frame_ && flow_at(flow, p.last.uv, &predicted);
    if (by_flow) {
      radius = options_.flow_radius_px;  // eq. 4's search around the flow prediction
    } else if (in_front) {
      predicted = projected;
      // a newborn cluster has no velocity yet: its prediction is where it was, so without
      // flow a fast car lies farther away than the motion model's window
      radius = options_.projection_radius_px * (newborn ? kNewbornSearchScale : 1.0);
    } else {
      continue;
    }
    const double scale = level_scale(p.last.octave);
    frame.grid.query(predicted.x(), predicted.y(), radius * scale, &candidates);
    // the flow has already located the point: a looser descriptor test only rejects
    // keypoints of other surfaces inside the small window
    const int max_distance = by_flow ? options_.flow_max_hamming : options_.max_hamming;
    int best = -1, best_distance = max_distance + 1;
    for (int k : candidates) {
      if (claimed_by_[k] >= 0) continue;
      const int d = map::hamming(p.descriptor, frame.keypoints.descriptors[k]);
      if (d < best_distance) best = k, best_distance = d;
    }
    if (best < 0) continue;
    matches.push_back({i, best, best_distance});
  }
  // one point per keypoint: the closest descriptor keeps it
  std::sort(matches.begin(), matches.end(), [](const Match& a, const Match& b) {
    return a.keypoint != b.keypoint ? a.keypoint < b.keypoint : a.distance < b.distance;
  });
  matches.erase(std::unique(matches.begin(), matches.end(),
                            [](const Match& a, const Match& b) { return a.keypoint == b.keypoint; }),
                matches.end());
  for (const Match& m : matches) evidence->shared.add(instance_of_keypoint_[m.keypoint]);
  return matches;
}

bool ObjectTracker::keypoint_allowed(int k, int instance) const {
  if (claimed_by_[k] >= 0) return false;
  const int on = instance_of_keypoint_[k];
  if (instance >= 0) return on == instance;
  // no mask this frame: anything but another cluster's instance
  return on <= 0 || !assigned_instances_.count(on);
}

void ObjectTracker::refine_matches(const objects::ObjectCluster& cluster, const Mat4& T_c_o,
                                   const Frame& frame, int instance,
                                   std::vector<Match>* matches) const {
  std::vector<std::uint8_t> matched(cluster.points.size(), 0), used(frame.keypoints.size(), 0);
  for (const Match& m : *matches) matched[m.point] = 1, used[m.keypoint] = 1;
  std::vector<int> candidates;
  for (int i = 0; i < static_cast<int>(cluster.points.size()); ++i) {
    if (matched[i]) continue;
    const objects::ObjectPoint& p = cluster.points[i];
    const Vec3 X_c = transform(T_c_o, p.X_o);
    if (X_c.z() <= 0.1) continue;
    const Vec2 uv = camera_.project(X_c);
    if (!camera_.in_image(uv)) continue;
    const double scale = level_scale(p.last.octave);
    frame.grid.query(uv.x(), uv.y(), options_.refine_radius_px * scale, &candidates);
    int best = -1, best_distance = options_.max_hamming + 1;
    for (int k : candidates) {
      if (used[k] || !keypoint_allowed(k, instance)) continue;
      const int d = map::hamming(p.descriptor, frame.keypoints.descriptors[k]);
      if (d < best_distance) best = k, best_distance = d;
    }
    if (best < 0) continue;
    used[best] = 1;
    matches->push_back({i, best, best_distance});
  }
}

}  // namespace twistslam::tracking
