#include "objects/track_turn.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/se3.hpp"
#include "geometry/so3.hpp"

namespace twistslam::objects {

double mean_turn_deg_per_frame(const ObjectTrack& track) {
  const int rows = static_cast<int>(track.frames.size());
  if (rows < 2) return 0.0;
  double turned_rad = 0;
  for (int r = 1; r < rows; ++r)
    turned_rad += geometry::so3_log(track.frames[r].T_w_o.topLeftCorner<3, 3>() *
                                    track.frames[r - 1].T_w_o.topLeftCorner<3, 3>().transpose())
                      .norm();
  const int steps = std::max(track.frames.back().frame - track.frames.front().frame, 1);
  return turned_rad * 180.0 / M_PI / steps;
}

bool level_made_up_turn(ObjectTrack* track, double max_deg_per_frame) {
  if (!(max_deg_per_frame > 0) || mean_turn_deg_per_frame(*track) <= max_deg_per_frame) return false;
  const Mat3 R_w_o = track->last().T_w_o.topLeftCorner<3, 3>();
  for (TrackFrame& row : track->frames) row.T_w_o.topLeftCorner<3, 3>() = R_w_o;
  // eq. 2: T_w_o(i+1) = exp(Pi xi_i) T_w_o(i), the levelled twists translations only
  for (size_t r = 0; r + 1 < track->frames.size(); ++r)
    track->frames[r].xi = track->Pi * geometry::twist_between(track->frames[r].T_w_o, track->frames[r + 1].T_w_o);
  return true;
}

}  // namespace twistslam::objects
