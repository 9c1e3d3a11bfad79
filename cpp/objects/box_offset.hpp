#pragma once
// The constant offset between an object frame and its detected boxes: T_w_o_k C ~ T_w_det_k
// over the frames k with a box, so each frame gives a sample C_k = T_w_o_k^-1 T_w_det_k (in
// the object frame). A rigid object has one C; its samples scatter by the detector's noise,
// which grows with range. Their weighted robust mean re-anchors a canonical frame that the
// first box alone set (TwistSLAM++: "the first detection sets the object frame, later refined").
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::objects {

struct BoxOffsetSample {
  Mat4 T_o_box = Mat4::Identity();  // C_k: the box pose in the object frame of its frame
  double weight = 1;                // > 0, e.g. 1 / sigma_k^2 of the box's centre
};

struct BoxOffsetOptions {
  double inlier_translation_m = 1.0;  // samples this far from the first mean are left out
  double inlier_rotation_rad = 0.26;  // ... or turned this much (15 deg) from it
  // samples turned more than this from the identity never count: the object frame is a box
  // frame, so a box turned by ~pi is the same box with its heading the other way
  double max_rotation_rad = 1.57;
};

struct BoxOffset {
  bool valid = false;               // at least one inlier
  Mat4 T_o_box = Mat4::Identity();  // the weighted mean offset C
  int inliers = 0;
};

// Weighted mean of the offsets turned less than max_rotation_rad (translations averaged,
// rotations averaged in the tangent space at the identity), then again over the samples near
// that first mean.
BoxOffset mean_box_offset(const std::vector<BoxOffsetSample>& samples,
                          const BoxOffsetOptions& options = {});

}  // namespace twistslam::objects
