#pragma once
// The points of an object cluster (paper sec. "Clusters creation"): 3D points in the object
// frame o, with the descriptor and the last 2D observation that visual tracking (eq. 4)
// searches from. The cluster's pose, twist and lifetime are its ObjectTrack (object_track.hpp):
// one object state for the detections tracker, visual tracking and LiDAR fusion.
#include <vector>

#include "geometry/types.hpp"
#include "map/descriptor.hpp"
#include "objects/label_votes.hpp"

namespace twistslam::objects {

struct ObjectPointObservation {
  int frame = -1;
  Vec2 uv = Vec2::Zero();  // px, left image
  double u_right = -1;     // px; < 0: mono
  int octave = 0;
};

struct ObjectPoint {
  Vec3 X_o = Vec3::Zero();  // in the object frame (moves with the object)
  // where it joined its cluster (same frame, re-expressed with X_o): windows may refine X_o
  // within a fraction of its depth of this place (ObjectTrackingOptions)
  Vec3 X_o_placed = Vec3::Zero();
  map::Descriptor descriptor{};
  ObjectPointObservation last;  // the latest observation (flow-guided search starts here)
  std::vector<ObjectPointObservation> history;  // the latest ones, oldest first (window BA)
  std::vector<ObjectPointObservation> keyframe_history;  // those at keyframes (local BA's e_dyna)
  // every inlier observation since it was created, oldest first: the final smoothing's e_dyna
  // over the whole track (kept only while the tracker's final_smoothing is on)
  std::vector<ObjectPointObservation> archive;
  int visible = 1;              // frames in which it was predicted inside the image
  int found = 1;                // frames in which it was matched and an inlier
  // observations with a disparity (its creation's included): a point placed without one (at
  // its mask's ground contact, or its nearest stereo neighbour's depth) holds a guessed depth
  int stereo_seen = 0;
  LabelVotes class_votes;       // classes of its 2D observations (S3LAM-style vote)

  double found_ratio() const { return visible > 0 ? static_cast<double>(found) / visible : 0.0; }
};

struct ObjectCluster {
  int track_id = -1;              // its ObjectTrack
  std::vector<ObjectPoint> points;
  LabelVotes class_votes;         // classes of the instances associated with it
  int instance = -1;              // instance id associated in the last frame (-1: none)
  Vec6 velocity = Vec6::Zero();   // last estimated twist (per frame), for the prediction
  // points culled or replaced while the object was tracked, with their archives (final
  // smoothing): a car that turns shows other faces, and the ones it showed before still fix
  // its earlier poses. Re-expressed with every change of the object frame, never searched.
  std::vector<ObjectPoint> retired;
};

}  // namespace twistslam::objects
