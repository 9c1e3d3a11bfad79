#include "tracking/projection_matcher.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

namespace twistslam::tracking {

int search_by_projection(Frame& frame, map::Map& map, const std::vector<int>& point_ids,
                         const geometry::StereoCamera& camera,
                         const std::vector<float>& scale_factors, const ProjectionSearch& search,
                         bool count_visible) {
  std::unordered_set<int> already;
  for (int pid : frame.point_ids)
    if (pid >= 0) already.insert(pid);
  const double max_scale = scale_factors.empty() ? 1.0 : scale_factors.back();
  std::vector<int> best_distance(frame.keypoints.size(), std::numeric_limits<int>::max());
  std::vector<int> candidates;
  const Mat3 R = frame.T_c_w.topLeftCorner<3, 3>();
  const Vec3 t = frame.T_c_w.topRightCorner<3, 1>();
  int matches = 0;

  for (int pid : point_ids) {
    if (already.count(pid) || !map.has_point(pid)) continue;
    map::MapPoint& point = map.point(pid);
    if (point.bad) continue;
    const Vec3 X_c = R * point.X_w + t;
    if (X_c.z() + camera.t_left.z() < 0.1) continue;  // behind the left camera
    const Vec2 uv = camera.project(X_c);
    if (!camera.in_image(uv)) continue;
    if (count_visible) ++point.visible;
    frame.grid.query(uv.x(), uv.y(), search.radius_px * max_scale, &candidates);
    const double u_right_pred = camera.project_right(X_c).x();

    int best = std::numeric_limits<int>::max(), second = best, best_idx = -1, best_level = -1,
        second_level = -1;
    for (int i : candidates) {
      if (!frame.usable[i] || frame.point_ids[i] >= 0) continue;
      const int level = frame.keypoints.octave[i];
      const double radius = search.radius_px * scale_factors[std::min<size_t>(level, scale_factors.size() - 1)];
      if ((frame.keypoints.uv[i] - uv).norm() > radius) continue;
      if (frame.keypoints.u_right[i] >= 0 && std::abs(frame.keypoints.u_right[i] - u_right_pred) > radius)
        continue;  // the stereo match disagrees with the predicted depth
      const int d = map::hamming(point.descriptor, frame.keypoints.descriptors[i]);
      if (d < best) {
        second = best, second_level = best_level;
        best = d, best_idx = i, best_level = level;
      } else if (d < second) {
        second = d, second_level = level;
      }
    }
    if (best_idx < 0 || best > search.max_hamming) continue;
    if (best_level == second_level && best > search.ratio * second) continue;  // ambiguous
    if (best >= best_distance[best_idx]) continue;  // the keypoint has a closer point already
    best_distance[best_idx] = best;
    // matches are only written once all points are done, so a better later point can replace
    frame.outlier[best_idx] = 0;
    frame.point_ids[best_idx] = -2 - pid;  // provisional: -2 - pid
  }
  for (size_t i = 0; i < frame.point_ids.size(); ++i) {
    if (frame.point_ids[i] <= -2) {
      frame.point_ids[i] = -2 - frame.point_ids[i];
      ++matches;
    }
  }
  return matches;
}

}  // namespace twistslam::tracking
