#include "objects/box_axis_rank.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/se3.hpp"

namespace twistslam::objects {

int axis_rank(bool prior_length, const Mat4& T_w_box, const Mat4& T_w_c, double min_angle_deg) {
  if (!prior_length) return 2;
  const Vec3 sight_w = T_w_box.topRightCorner<3, 1>() - T_w_c.topRightCorner<3, 1>();
  const double cos_to_sight = std::abs(T_w_box.block<3, 1>(0, 0).dot(sight_w)) / sight_w.norm();
  return cos_to_sight <= std::cos(min_angle_deg * M_PI / 180.0) ? 1 : 0;
}

int track_axis_rank(const ObjectTrack& track, double min_angle_deg) {
  int best = -1;
  for (const TrackFrame& row : track.frames)
    if (row.has_detection())
      best = std::max(best, axis_rank(!row.open_end_w.isZero(), row.T_w_o_detected,
                                      geometry::se3_inverse(row.T_c_w), min_angle_deg));
  return best;
}

}  // namespace twistslam::objects
