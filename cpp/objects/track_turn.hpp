#pragma once
// How fast a track's rows turn, and levelling a turn a cluster made up (tracking's first box,
// object_canonical.cpp): a far cluster's twist from a handful of points can spin its frame by
// ~10 deg/frame while the car drives straight; no car turns that fast at 10 Hz.
#include "objects/object_track.hpp"

namespace twistslam::objects {

// Mean rotation per frame between the track's consecutive rows (deg/frame; rows are
// consecutive frames, a gap counts its frames); 0 with fewer than two rows.
double mean_turn_deg_per_frame(const ObjectTrack& track);

// When the rows turn faster than max_deg_per_frame on average (> 0), every row takes the last
// row's rotation, keeps its position (the track's path is measured, its turn was not) and the
// twists of eq. 2 are recomputed between the levelled rows. Returns whether it levelled.
bool level_made_up_turn(ObjectTrack* track, double max_deg_per_frame);

}  // namespace twistslam::objects
