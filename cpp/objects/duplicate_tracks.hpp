#pragma once
// Two tracks on one object in one frame: the camera side can start a second cluster on a car
// already tracked (a split mask, a re-seeded instance), and the one-to-one box association
// then feeds only one of them; the other lives on with whatever frame its few boxes gave it.
// A track whose origin lies in another's canonical box footprint is the same object; the one
// whose boxes know the car's axis better (box_axis_rank.hpp), then the one with more boxes, is
// the object, the other a duplicate (not reported in that frame).
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::objects {

struct TrackFootprint {
  Mat4 T_w_o = Mat4::Identity();  // this frame's pose (origin: box centre when canonical)
  Vec3 size = Vec3::Zero();       // l, w, h (m); a box only when canonical and positive
  bool canonical = false;         // the object frame is a box frame
  int class_id = -1;
  int boxes = 0;                  // detections associated over the track's life
  int axis_rank = -1;             // the best axis rank of those boxes (-1: none)
};

// Per track: the index of the track whose footprint holds its origin (-1: none). A footprint
// is a canonical track's length x width (the height is not compared: both stand on the road),
// grown by margin_m, of the same class, and it holds only tracks it ranks above: a better
// axis rank, then more boxes, then earlier in the list. Of several such owners, the highest ranked. margin_m < 0: none.
std::vector<int> duplicate_owners(const std::vector<TrackFootprint>& tracks, double margin_m);

}  // namespace twistslam::objects
