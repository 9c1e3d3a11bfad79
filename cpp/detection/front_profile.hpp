#pragma once
// Which end of a car is its front, from the height profile of its LiDAR returns along its
// length: the greenhouse (windows and roof, the upper part of a car) sits behind the middle,
// the hood ahead of it is longer than the trunk behind it (sedans: hood ~1.1 m, trunk
// ~0.9 m plus a flatter rear window; hatchbacks, SUVs and vans have almost no trunk). The
// L-shape fit knows the heading mod pi only; this tells front from back for a car whose whole
// length was seen. Measured in docs/detection.md (real KITTI and simulated cars).
#include <vector>

#include "detection/classify.hpp"
#include "detection/detector_options.hpp"

namespace twistslam::detection {

struct ProfilePoint {
  float along = 0;  // m, along the box's heading (from its centre)
  float up = 0;     // m, above the road
};

// +1: the front lies towards +along; -1: towards -along; 0: undecided (too few returns, no
// upper returns, or the gaps ahead of and behind the greenhouse differ by less than
// front_profile_min_gap_difference_m).
int front_from_profile(const std::vector<ProfilePoint>& points, const DetectorOptions& options);

// The hood-minus-trunk gap (m): the gap from the greenhouse to the +along end of the returns
// minus the one to the -along end (> 0: the front lies towards +along), with the greenhouse the
// returns above upper_fraction of the car's top. NaN with too few returns or upper returns.
// One view's difference scatters by ~0.15 m (simulated side views at 16-29 m); a track
// averages its views' (tracking/object_front_profile.cpp).
double profile_gap_difference(const std::vector<ProfilePoint>& points, double upper_fraction);

// The front from several views' gap differences (NaN ones skipped): +1 / -1 when at least
// min_views are finite and their mean lies at least min_sigmas standard errors and
// min_difference_m from 0 (on its side); else 0.
int front_from_views(const std::vector<double>& differences, int min_views, double min_sigmas,
                     double min_difference_m);

// A car whose whole length was seen (length_seen) gets its front: heading_known is set and its
// yaw turned by pi if the front lies at its box's -x end (the yaw stays in [-pi, pi)).
// `profile`: its returns along its box's heading. A hidden end (shape.hidden_*_azimuth: what
// hides it may have hidden a lid too) decides only if the profile puts the front there.
void tell_front(Detection& car, const ClusterShape& shape, const std::vector<ProfilePoint>& profile,
                const DetectorOptions& options);

}  // namespace twistslam::detection
