#pragma once
// How far, and which way, a track's detected boxes travelled: a line fitted to the box
// centres over their frames (least squares, then again without the centres far from the
// first line). A box's heading is known mod pi, a car drives forward: the fitted direction
// settles the heading. The first box alone cannot: a wrong first box (another car's, a
// false positive 2 m off) turned a correct frame around (oracle urban seed 1).
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::objects {

struct BoxCentre {
  int frame = 0;
  Vec3 centre_w = Vec3::Zero();  // the box centre in the world frame
};

struct BoxTravelOptions {
  // centres this far from the first fitted line are left out of the second fit (a wrong
  // box, m); a LiDAR box centre scatters by ~0.1-0.5 m
  double outlier_m = 1.0;
};

struct BoxTravel {
  bool valid = false;               // at least two inlier centres at distinct frames
  Vec3 velocity_w = Vec3::Zero();   // m/frame, the fitted line's slope
  double distance_m = 0;            // |velocity| x the inliers' frame span
  // standard error of distance_m: the inliers' scatter about the line along its direction
  // (n - 2 degrees of freedom) over sqrt(sum (f - mean f)^2), x the span; infinite below
  // kTravelSigmaMinInliers inliers (a median of fewer is too unsure: at 4 boxes a parked car
  // "drove" 5 sigmas in ~3 % of trials). A far car's boxes scatter by ~0.6 m: a car that crept
  // 0.5 m "travelled" 1.5 m the wrong way (urban seed 4's car 20)
  double distance_sigma_m = 0;
  int inliers = 0;
};
constexpr int kTravelSigmaMinInliers = 6;

BoxTravel box_travel(const std::vector<BoxCentre>& centres, const BoxTravelOptions& options = {});

}  // namespace twistslam::objects
