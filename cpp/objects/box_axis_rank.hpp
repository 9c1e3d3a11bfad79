#pragma once
// How well a track's 3D boxes know the car's length axis. A box whose length is the
// detector's prior (Detection::open_end != 0) saw one face: laid along a face seen across the
// line of sight (a side), its axis is the car's; laid away from a face seen end-on (a rear,
// or a partly hidden side read as one), its axis is a guess. The detection fusion lets a box
// that knows the axis better turn a track's frame (tracking/object_detection_fusion.cpp); the
// duplicate rule keeps the track whose boxes know it better (duplicate_tracks.hpp).
#include "geometry/types.hpp"
#include "objects/object_track.hpp"

namespace twistslam::objects {

// 2 a measured length (an L-shape, or a detector that sees the whole car); 1 a prior length
// laid along a face at least min_angle_deg off the line of sight from the camera T_w_c; 0 a
// prior length laid away from a face seen end-on.
int axis_rank(bool prior_length, const Mat4& T_w_box, const Mat4& T_w_c, double min_angle_deg);

// The best axis rank among the track's boxes (-1: no box).
int track_axis_rank(const ObjectTrack& track, double min_angle_deg);

}  // namespace twistslam::objects
