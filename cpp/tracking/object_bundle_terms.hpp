#pragma once
// The object half of the keyframe BA (paper eq. 9: e_dyna and the link): whoever holds the
// moving objects (the ObjectTracker) adds their poses at the window's keyframes, their points
// and keypoints to the BA problem, so that they inform the camera poses, and takes the
// results back. An interface, so that
// local mapping does not depend on the object tracker.
#include <map>

#include "optim/bundle_adjustment.hpp"

namespace twistslam::tracking {

class ObjectBundleTerms {
 public:
  virtual ~ObjectBundleTerms() = default;
  // slot_of_frame: frame index of each keyframe in the problem -> its index in
  // problem->keyframes; max_points: per object (< 0: all). Appends to problem->objects and
  // problem->dynamic_observations.
  virtual void add_bundle_terms(const std::map<int, int>& slot_of_frame, int max_points,
                                optim::BAProblem* problem) = 0;
  // After bundle_adjust(problem): the dropped outliers and the refined keyframe poses (the
  // camera poses the objects were tracked against).
  virtual void take_bundle_result(const optim::BAProblem& problem,
                                  const optim::BundleAdjustmentReport& report) = 0;
};

}  // namespace twistslam::tracking
