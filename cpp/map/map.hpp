#pragma once
// The map: keyframes and map points with their bidirectional observation links.
// Single-threaded by design (tracking and local mapping run in one loop), so no locks.
#include <unordered_map>
#include <vector>

#include "map/keyframe.hpp"
#include "map/map_point.hpp"

namespace twistslam::map {

class Map {
 public:
  KeyFrame& add_keyframe(KeyFrame keyframe);  // assigns the id
  MapPoint& add_point(const Vec3& X_w, const Descriptor& descriptor, int first_keyframe);

  // Links point <-> keypoint of a keyframe (replaces what that keypoint pointed to).
  void add_observation(int point_id, int keyframe_id, int keypoint);
  void erase_observation(int point_id, int keyframe_id);
  // Removes the point and every keyframe link to it.
  void erase_point(int point_id);

  // Recounts the points a keyframe shares with every other keyframe (both directions).
  void update_covisibility(int keyframe_id);
  // Up to n keyframes sharing the most points with keyframe_id, best first.
  std::vector<int> covisible_keyframes(int keyframe_id, int n, int min_shared = 1) const;
  // Re-chooses the point's descriptor: the observation with the least median distance.
  void update_descriptor(int point_id);

  bool has_point(int id) const { return points_.count(id) > 0; }
  bool has_keyframe(int id) const { return keyframes_.count(id) > 0; }
  MapPoint& point(int id) { return points_.at(id); }
  const MapPoint& point(int id) const { return points_.at(id); }
  KeyFrame& keyframe(int id) { return keyframes_.at(id); }
  const KeyFrame& keyframe(int id) const { return keyframes_.at(id); }
  const std::unordered_map<int, MapPoint>& points() const { return points_; }
  const std::unordered_map<int, KeyFrame>& keyframes() const { return keyframes_; }
  std::vector<int> keyframe_ids() const;  // ascending (= insertion order)
  size_t num_points() const { return points_.size(); }
  size_t num_keyframes() const { return keyframes_.size(); }
  void clear();

 private:
  std::unordered_map<int, KeyFrame> keyframes_;
  std::unordered_map<int, MapPoint> points_;
  int next_keyframe_id_ = 0;
  int next_point_id_ = 0;
};

}  // namespace twistslam::map
