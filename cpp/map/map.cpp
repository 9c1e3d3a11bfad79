#include "map/map.hpp"

#include <algorithm>

namespace twistslam::map {

int KeyFrame::num_tracked_points() const {
  return static_cast<int>(std::count_if(point_ids.begin(), point_ids.end(), [](int p) { return p >= 0; }));
}

KeyFrame& Map::add_keyframe(KeyFrame keyframe) {
  keyframe.id = next_keyframe_id_++;
  keyframe.point_ids.resize(keyframe.keypoints.size(), -1);
  return keyframes_.emplace(keyframe.id, std::move(keyframe)).first->second;
}

MapPoint& Map::add_point(const Vec3& X_w, const Descriptor& descriptor, int first_keyframe) {
  MapPoint p;
  p.id = next_point_id_++;
  p.X_w = X_w;
  p.descriptor = descriptor;
  p.first_keyframe = first_keyframe;
  return points_.emplace(p.id, std::move(p)).first->second;
}

void Map::add_observation(int point_id, int keyframe_id, int keypoint) {
  KeyFrame& kf = keyframes_.at(keyframe_id);
  const int previous = kf.point_ids.at(keypoint);
  if (previous == point_id) return;
  if (previous >= 0 && points_.count(previous)) points_.at(previous).observations.erase(keyframe_id);
  MapPoint& p = points_.at(point_id);
  const auto old = p.observations.find(keyframe_id);
  if (old != p.observations.end()) kf.point_ids[old->second] = -1;  // one keypoint per keyframe
  p.observations[keyframe_id] = keypoint;
  kf.point_ids[keypoint] = point_id;
}

void Map::erase_observation(int point_id, int keyframe_id) {
  MapPoint& p = points_.at(point_id);
  const auto it = p.observations.find(keyframe_id);
  if (it == p.observations.end()) return;
  keyframes_.at(keyframe_id).point_ids[it->second] = -1;
  p.observations.erase(it);
}

void Map::erase_point(int point_id) {
  const auto it = points_.find(point_id);
  if (it == points_.end()) return;
  for (const auto& [kf_id, kp] : it->second.observations) {
    auto kf = keyframes_.find(kf_id);
    if (kf != keyframes_.end() && kf->second.point_ids[kp] == point_id) kf->second.point_ids[kp] = -1;
  }
  points_.erase(it);
}

void Map::update_covisibility(int keyframe_id) {
  KeyFrame& kf = keyframes_.at(keyframe_id);
  std::unordered_map<int, int> shared;
  for (int pid : kf.point_ids) {
    if (pid < 0) continue;
    for (const auto& obs : points_.at(pid).observations)
      if (obs.first != keyframe_id) ++shared[obs.first];
  }
  for (const auto& [other, _] : kf.covisibility)  // drop links that vanished
    if (!shared.count(other) && keyframes_.count(other)) keyframes_.at(other).covisibility.erase(keyframe_id);
  kf.covisibility.clear();
  for (const auto& [other, count] : shared) {
    kf.covisibility[other] = count;
    keyframes_.at(other).covisibility[keyframe_id] = count;
  }
}

std::vector<int> Map::covisible_keyframes(int keyframe_id, int n, int min_shared) const {
  std::vector<std::pair<int, int>> ranked;  // (shared, id)
  for (const auto& [other, count] : keyframes_.at(keyframe_id).covisibility)
    if (count >= min_shared) ranked.emplace_back(count, other);
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second > b.second;  // ties: newer first
  });
  std::vector<int> out;
  for (size_t i = 0; i < ranked.size() && static_cast<int>(i) < n; ++i) out.push_back(ranked[i].second);
  return out;
}

void Map::update_descriptor(int point_id) {
  MapPoint& p = points_.at(point_id);
  std::vector<const Descriptor*> ds;
  for (const auto& [kf_id, kp] : p.observations) ds.push_back(&keyframes_.at(kf_id).keypoints.descriptors[kp]);
  if (ds.size() < 2) return;
  int best = 0, best_median = 1 << 30;
  for (size_t i = 0; i < ds.size(); ++i) {
    std::vector<int> d;
    for (size_t j = 0; j < ds.size(); ++j)
      if (j != i) d.push_back(hamming(*ds[i], *ds[j]));
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    if (d[d.size() / 2] < best_median) best_median = d[d.size() / 2], best = static_cast<int>(i);
  }
  p.descriptor = *ds[best];
}

std::vector<int> Map::keyframe_ids() const {
  std::vector<int> ids;
  ids.reserve(keyframes_.size());
  for (const auto& [id, _] : keyframes_) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

void Map::clear() {
  keyframes_.clear();
  points_.clear();
  next_keyframe_id_ = next_point_id_ = 0;
}

}  // namespace twistslam::map
