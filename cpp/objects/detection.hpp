#pragma once
// One 3D detection of a frame, as the detections tracker (tracker.hpp) and the LiDAR fusion
// of the visual object tracking (tracking/object_detection_fusion.cpp) take it.
#include "geometry/box3d.hpp"

namespace twistslam::objects {

struct Detection {
  geometry::Box3D box;  // in the camera frame of its frame (geometric centre, KITTI yaw)
  double score = 0;
  int class_id = 0;     // tracks and detections associate within a class only
  bool planar = true;   // the class moves on the ground plane (planar link), else free
  // 0: the box's length was measured (or unknown); +1 / -1: a partly seen car, its length the
  // detector's prior laid from the seen face towards the box's +x / -x end (x: the heading)
  int open_end = 0;
  // the box is the tight extent of its LiDAR points (the classical detector): a measured length
  // is a lower bound, and the box's end nearer the sensor is the seen one
  bool point_extent = false;
  // the box's heading points to the object's front (a point extent knows it mod pi unless the
  // detector told the front from the car's height profile)
  bool heading_known = true;
};

}  // namespace twistslam::objects
