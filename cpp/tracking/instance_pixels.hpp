#pragma once
// Reading per-pixel images at keypoints: instance ids (CV_32SC1, 0: no instance) and
// optical flow (CV_32FC2).
#include <opencv2/core/mat.hpp>

#include "geometry/types.hpp"

namespace twistslam::tracking {

// The value at the pixel nearest uv; 0 outside the image.
int pixel_value(const cv::Mat& image, const Vec2& uv);

// The instance at a keypoint, or 0 when a pixel of another instance lies within radius_px
// (a box of that half size, rounded up) of it. At an occlusion boundary between two objects
// the corner and its stereo depth may be the nearer object's: on the simulator a far car's
// keypoints just above the roof of a car in front of it took that car's 20-24 px disparity
// instead of their own 11.5 px, and its cluster started 5.6 m short. Unlabelled pixels (0:
// the static background) do not count: a car's silhouette against the sky or a wall is the
// car's own (the car is the nearer surface). radius_px <= 0: the pixel's value alone.
int instance_at_keypoint(const cv::Mat& instances, const Vec2& uv, double radius_px);

// The pixel uv moves to by the flow (bilinear, CV_32FC2 u, v per pixel); false where the
// flow is empty or missing (NaN) or uv lies outside the image.
bool flow_at(const cv::Mat& flow, const Vec2& uv, Vec2* out);

}  // namespace twistslam::tracking
