#pragma once
// Depths for the keypoints of a vehicle mask that the stereo matcher left without one (not in
// the paper). A car queued beside or behind a nearer one is often seen by the left camera
// alone: the right one looks past the occluder at another angle. Crowded seed 3's cars 17 and
// 81 (15-22 m) showed 5-18 keypoints in their masks and 2-8 stereo depths among them; a
// cluster started from its 6 stereo points then found fewer than 6 of them in the next frame
// and failed, frame after frame (coverage 0.19 and 0.61). Their lower edges were hidden, so
// the ground contact gave no depth either.
// Each such keypoint takes the depth of the stereo keypoint of the same mask nearest to it in
// the image: a car's surface is smooth at the scale of its keypoint spacing, and the nearest
// stereo point lies on the same face (a car seen at an angle shows its rear and a side, whose
// depths differ by metres; one depth for the whole mask gave crowded s3's car 81 an RPE_r of
// 0.95 deg/m, the nearest one 0.44). The points join the cluster as mono points (eq. 4
// reprojection only); the window refines their positions with the motion.
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::tracking {

struct StereoDepthFillOptions {
  int min_stereo_points = 3;       // stereo depths the mask must hold
  double max_median_depth_m = 30;  // their median: farther, no fill
  double min_stereo_share = 0.15;  // of the mask's keypoints: fewer, the stereo failed wholesale
};

// stereo_uv / stereo_depth: the mask's keypoints with a stereo depth (px, m); mono_uv: those
// without. Returns, per mono keypoint, the depth of its nearest stereo keypoint in the image;
// empty when fewer than min_stereo_points depths are finite and positive, when their median
// lies beyond max_median_depth_m (a far car's few disparities are metres off: urban seed 4's
// cars at 39-60 m started 2.7-3.3 m short, ghosts), or when they are under min_stereo_share of
// all the keypoints (real 0001: a car passing at 4-6 m on the image border had 3 stereo depths
// among 253 keypoints, at 8-9 m; filled, it was placed 1.6 m too far). Non-finite entries are
// skipped.
// Throws std::invalid_argument when stereo_uv and stereo_depth differ in size.
std::vector<double> nearest_stereo_depths(const std::vector<Vec2>& stereo_uv,
                                          const std::vector<double>& stereo_depth,
                                          const std::vector<Vec2>& mono_uv,
                                          const StereoDepthFillOptions& options);

}  // namespace twistslam::tracking
