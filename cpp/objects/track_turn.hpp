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

}  // namespace twistslam::objects
