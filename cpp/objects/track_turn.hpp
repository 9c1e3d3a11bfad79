#pragma once
// How fast a track's rows turn, and levelling a turn a cluster made up (tracking's first box,
// object_canonical.cpp): a far cluster's twist from a handful of points can spin its frame by
// ~10 deg/frame while the car drives straight; no car turns that fast at 10 Hz. And bounding
// each row's turn by the distance it travelled (camera-only tracks' final rows,
// object_windows.cpp): a car turns only as it drives.
#include "objects/object_track.hpp"

namespace twistslam::objects {

// Mean rotation per frame between the track's consecutive rows (deg/frame; rows are
// consecutive frames, a gap counts its frames); 0 with fewer than two rows.
double mean_turn_deg_per_frame(const ObjectTrack& track);

// When the rows turn faster than max_deg_per_frame on average (> 0), every row takes the last
// row's rotation, keeps its position (the track's path is measured, its turn was not) and the
// twists of eq. 2 are recomputed between the levelled rows. Returns whether it levelled.
bool level_made_up_turn(ObjectTrack* track, double max_deg_per_frame);

// A car turns only as it travels: its heading changes by at most (distance travelled) /
// (turning radius). Each row's rotation since the previous row is shortened to
// |t_r - t_r-1| / min_turn_radius_m (rad) when larger, the rows' positions kept (the track's
// path is measured; a far camera-only cluster's spin about the vertical is not: the twist of a
// car seen nearly end-on hardly observes it, and e_const keeps a constant spin). The twists
// of eq. 2 are recomputed. Returns the number of rows whose rotation changed (0 when
// min_turn_radius_m <= 0).
int bound_turn_by_travel(ObjectTrack* track, double min_turn_radius_m);

// A car heads where its path goes: over a track, its heading turns as far as the direction of
// its path does. The path's direction at each end is the chord over its first / last chord_m
// of travel (reported rows, in the plane normal to up_w); the chords must not overlap. When
// they point within max_path_turn_deg of each other (the car drove straight) while the rows'
// rotation about up_w turned by at least min_excess_deg more than the path did, the turn is
// made up: a far camera-only cluster seen side-on keeps its orientation towards the camera and
// its frame turns with its bearing (urban s23's car 17: -51 deg while the bearing turned -48
// and the car drove straight). Every row then takes the rotation of the middle reported row,
// positions kept, and eq. 2's twists are recomputed. Returns whether it levelled (never with
// chord_m <= 0, min_excess_deg <= 0 or a zero up_w).
bool level_turn_off_its_path(ObjectTrack* track, const Vec3& up_w, double chord_m,
                             double max_path_turn_deg, double min_excess_deg);

}  // namespace twistslam::objects
