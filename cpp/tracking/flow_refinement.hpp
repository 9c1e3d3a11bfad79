// Lucas-Kanade refinement of flow-predicted pixels (visual_objects.flow_observations_lk_max_px).
// A point located by a dense flow frame after frame chains the flow's error: DIS is a few
// tenths of a pixel off on a car, and a far lead car's points slid along its body by metres
// over 80 frames (docs/visual_objects.md). Refined on the point's own patch, from its last
// pixel, the error no longer chains.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "geometry/types.hpp"

namespace twistslam::tracking {

// The two left images' pyramids with their derivatives, built once per frame.
struct LkPyramids {
  std::vector<cv::Mat> previous, current;
  bool empty() const { return previous.empty() || current.empty(); }
};

// previous, current: 8-bit gray images of one size; throws std::invalid_argument otherwise.
LkPyramids build_lk_pyramids(const cv::Mat& previous, const cv::Mat& current);
// The same with the previous image's pyramid already built (the last frame's current one,
// as build_lk_pyramids made it): only the current image's is built.
LkPyramids build_lk_pyramids(const std::vector<cv::Mat>& previous_pyramid, const cv::Mat& current);

// Each pixel from[k] of the previous image, predicted at (*to)[k] in the current one, is
// refined there by pyramidal Lucas-Kanade; kept[k] = 1 and (*to)[k] moved where it converged
// within max_px of the prediction, kept[k] = 0 (and (*to)[k] unchanged) where it failed or
// went farther. from and *to of one size; throws std::invalid_argument otherwise.
std::vector<char> refine_flow_pixels(const LkPyramids& pyramids, const std::vector<Vec2>& from,
                                     std::vector<Vec2>* to, double max_px);

}  // namespace twistslam::tracking
