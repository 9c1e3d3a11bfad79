#pragma once
// A frame's pose without a position prior: its keypoints matched to map points by descriptor
// alone, then PnP RANSAC on the left image. The camera tracker's prediction for the frame after
// a map start, where no velocity is known yet (as ORB-SLAM tracks against its reference
// keyframe by descriptors there): "no motion" is a whole frame of driving off.
#include <optional>
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "map/map.hpp"
#include "tracking/frame.hpp"

namespace twistslam::tracking {

struct DescriptorPoseOptions {
  int max_hamming = 40;         // bits: a match at most this far (the motion search's)
  double ratio_test = 0.7;      // best / second best distance over all keypoints
  double max_reprojection_px = 2.0;  // RANSAC inlier threshold (level-0 px)
  int ransac_iterations = 200;
  int min_inliers = 20;         // fewer: no pose (the caller keeps its prediction)
};

struct DescriptorPose {
  Mat4 T_c_w = Mat4::Identity();
  int matches = 0;   // descriptor matches that passed the ratio test
  int inliers = 0;   // of those, RANSAC's inliers
};

// T_c_w of `frame` from its keypoints' descriptor matches to `point_ids` of `map`; nullopt with
// fewer than options.min_inliers RANSAC inliers (or fewer matches than a minimal set).
std::optional<DescriptorPose> pose_from_descriptors(const Frame& frame, const map::Map& map,
                                                    const std::vector<int>& point_ids,
                                                    const geometry::StereoCamera& camera,
                                                    const DescriptorPoseOptions& options);

}  // namespace twistslam::tracking
