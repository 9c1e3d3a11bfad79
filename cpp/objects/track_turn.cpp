#include "objects/track_turn.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

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

int bound_turn_by_travel(ObjectTrack* track, double min_turn_radius_m) {
  const int rows = static_cast<int>(track->frames.size());
  if (!(min_turn_radius_m > 0) || rows < 2) return 0;
  int changed = 0;
  Mat3 R_previous_original = track->frames[0].T_w_o.topLeftCorner<3, 3>();
  for (int r = 1; r < rows; ++r) {
    Mat4& T = track->frames[r].T_w_o;
    const Mat3 R_original = T.topLeftCorner<3, 3>();
    const Vec3 turn = geometry::so3_log(R_original * R_previous_original.transpose());
    const double travelled_m =
        (T.topRightCorner<3, 1>() - track->frames[r - 1].T_w_o.topRightCorner<3, 1>()).norm();
    const double max_turn_rad = travelled_m / min_turn_radius_m;
    const double turn_rad = turn.norm();
    R_previous_original = R_original;
    if (turn_rad <= max_turn_rad && changed == 0) continue;  // rows so far as they were
    const Vec3 kept = turn_rad > max_turn_rad ? Vec3(turn * (max_turn_rad / turn_rad)) : turn;
    changed += turn_rad > max_turn_rad;
    T.topLeftCorner<3, 3>() =
        geometry::so3_exp(kept) * track->frames[r - 1].T_w_o.topLeftCorner<3, 3>();
  }
  if (changed == 0) return 0;
  for (int r = 0; r + 1 < rows; ++r)  // eq. 2 between the bounded rows
    track->frames[r].xi = track->Pi * geometry::twist_between(track->frames[r].T_w_o, track->frames[r + 1].T_w_o);
  return changed;
}

namespace {

// v projected onto the plane normal to up (a unit vector).
Vec3 in_plane(const Vec3& v, const Vec3& up) { return v - up * up.dot(v); }

// Signed angle (rad) from a to b about up, both in the plane normal to up.
double angle_about(const Vec3& a, const Vec3& b, const Vec3& up) {
  return std::atan2(up.dot(a.cross(b)), a.dot(b));
}

}  // namespace

bool level_turn_off_its_path(ObjectTrack* track, const Vec3& up_w, double chord_m,
                             double max_path_turn_deg, double min_excess_deg) {
  if (!(chord_m > 0) || !(min_excess_deg > 0) || !up_w.allFinite() || !(up_w.norm() > 0))
    return false;
  const Vec3 up = up_w.normalized();
  std::vector<int> rows;  // reported rows: what the track says it saw
  for (int r = 0; r < static_cast<int>(track->frames.size()); ++r)
    if (track->frames[r].reported) rows.push_back(r);
  if (rows.size() < 3) return false;
  auto position = [&](int k) { return in_plane(track->frames[rows[k]].T_w_o.topRightCorner<3, 1>(), up); };
  // the first row chord_m from the first one, and the last row chord_m from the last one
  const int n = static_cast<int>(rows.size());
  int first_end = -1, last_start = -1;
  for (int k = 1; k < n && first_end < 0; ++k)
    if ((position(k) - position(0)).norm() >= chord_m) first_end = k;
  for (int k = n - 2; k >= 0 && last_start < 0; --k)
    if ((position(n - 1) - position(k)).norm() >= chord_m) last_start = k;
  if (first_end < 0 || last_start < 0 || first_end > last_start) return false;  // overlapping
  const double path_turn = angle_about(position(first_end) - position(0),
                                       position(n - 1) - position(last_start), up);
  // the rows' turn about up, summed row to row (a turn past 180 deg stays one)
  double rows_turn = 0;
  for (int k = 1; k < n; ++k) {
    const Vec3 w = geometry::so3_log(track->frames[rows[k]].T_w_o.topLeftCorner<3, 3>() *
                                     track->frames[rows[k - 1]].T_w_o.topLeftCorner<3, 3>().transpose());
    rows_turn += up.dot(w);
  }
  const double deg = 180.0 / M_PI;
  if (std::abs(path_turn) * deg > max_path_turn_deg ||
      std::abs(rows_turn - path_turn) * deg < min_excess_deg)
    return false;
  const Mat3 R_w_o = track->frames[rows[n / 2]].T_w_o.topLeftCorner<3, 3>();
  for (TrackFrame& row : track->frames) row.T_w_o.topLeftCorner<3, 3>() = R_w_o;
  for (size_t r = 0; r + 1 < track->frames.size(); ++r)  // eq. 2 between the levelled rows
    track->frames[r].xi = track->Pi * geometry::twist_between(track->frames[r].T_w_o, track->frames[r + 1].T_w_o);
  return true;
}

}  // namespace twistslam::objects
