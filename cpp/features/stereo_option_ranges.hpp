#pragma once
// Valid range of every StereoOptions field (inclusive, the field's unit; see
// options/option_range.hpp). Checked where options enter the core (the Python bindings and
// tracking::check_options), so that no value reaches the matcher's float-to-int conversions
// out of range. The matcher's own check_options (stereo.cpp) tests a subset.
#include "features/stereo.hpp"

namespace twistslam::features {

template <typename Visit>
void for_each_option(StereoOptions& o, Visit&& visit) {
  visit("max_hamming", o.max_hamming, 0, 256);  // bits of a 256-bit descriptor
  // px: rectified rows agree to a few px; a band of +-64 px (a sixth of a KITTI image) matches
  // anything, and keeps floor(v +- row_radius * scale) inside int
  visit("row_radius", o.row_radius, 0.0, 64.0);
  visit("octave_tolerance", o.octave_tolerance, 0, 31);  // levels: at most 32 of them
  visit("patch_radius", o.patch_radius, 1, 15);          // px: the matcher's SAD window limit
  visit("patch_half_height", o.patch_half_height, 0, 15);
  visit("refine_range", o.refine_range, 1, 32);  // px: the matcher's SAD search limit
  // m: the disparity search reaches fx b / min_depth; 1 cm is ~38,000 px on KITTI already
  visit("min_depth", o.min_depth, 0.01, 10000.0);
  // m: 10 km is a disparity of 0.04 px on KITTI, far below any matching precision ("no limit")
  visit("max_depth", o.max_depth, 0.01, 10000.0);
  // x the frame's median SAD: 100x keeps every match (the check is off); > 0 keeps some
  visit("outlier_factor", o.outlier_factor, 0.001, 100.0);
  // x num_features for the right image: the matcher's own limit
  visit("right_features_factor", o.right_features_factor, 0.1, 16.0);
}

}  // namespace twistslam::features
