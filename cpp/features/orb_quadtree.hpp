#pragma once
// The quadtree that spreads ORB keypoints over one pyramid level (as ORB-SLAM2's
// DistributeOctTree): regions are split breadth-first (largest first, the most populated first
// among equals) until there are `wanted` non-empty regions or none can be split; each region
// then keeps its strongest corner. Internal to OrbExtractor (orb.cpp), declared here for tests.
#include <opencv2/core.hpp>

#include <vector>

namespace twistslam::features::detail {

// Indices into `candidates` (corners of one level, inside `region`) of at most `wanted`
// keypoints, one per quadtree leaf, in ascending order (deterministic).
std::vector<int> distribute_keypoints(const std::vector<cv::KeyPoint>& candidates,
                                      const cv::Rect2f& region, int wanted);

}  // namespace twistslam::features::detail
