#pragma once
// Half-occlusion: the strip of a far object just left of a nearer object's left edge is seen by
// the left camera only. The right camera, 0.54 m to the right, looks at that strip past the
// nearer object's left edge, which there covers it: a point at column u with disparity d is at
// u - d in the right image, and a nearer object whose left edge is at column a with disparity
// D covers the right image from a - D on, so every far point with a - u < D - d has no partner
// in the right image. A SAD match of such a point took whatever looked alike (the far object's
// texture farther left, the occluder's edge). Measured on 41 simulated sequences it fixed
// queued cars (crowded seed 4's car 77) but took every stereo point of cars wholly in the
// strip (urban seed 8's parked car at 47 m became a ghost), so the tracker's option is off by
// default (visual_objects.right_occlusion_check, docs/visual_objects.md).
#include <opencv2/core.hpp>

#include <vector>

#include "features/orb.hpp"
#include "features/stereo.hpp"

namespace twistslam::features {

// What drop_matches_occluded_in_right did.
struct RightOcclusionReport {
  int num_instances = 0;  // instances with a disparity (enough matched keypoints on them)
  int num_dropped = 0;    // keypoints whose match lost its depth
};

// For each keypoint of `which` with a depth on an instance (`instances`: CV_32SC1 ids at the
// level-0 size, 0 or negative = none), the row to its right is walked as far as the largest
// instance disparity reaches: a pixel of another instance whose disparity D (the median of the
// disparities of the matched keypoints of `which` on it, at least min_keypoints of them)
// exceeds the keypoint's disparity d by more than its distance (px) plus margin_px means the
// right camera cannot see the point: its match gets u_right = depth = -1. A nearer object of
// another id to the keypoint's left does not occlude it (the right camera looks past its right
// side from the other way), nor does an instance without enough matched keypoints. Throws
// std::invalid_argument on a bad instance image, a negative margin, min_keypoints < 1, or
// matches / indices that do not belong to the keypoints.
RightOcclusionReport drop_matches_occluded_in_right(const Keypoints& left,
                                                    const std::vector<int>& which,
                                                    const cv::Mat& instances, float margin_px,
                                                    int min_keypoints, StereoMatches* matches);

}  // namespace twistslam::features
