#pragma once
// The constant offset between measured stereo disparities and the disparities LiDAR depths
// imply: offset = median(fx b / z_lidar - d_measured). Stereo depth with it applied is
// Z = fx b / (d + offset). On the real KITTI colour pair the offset is about +0.6 px at all
// ranges (docs/lidar.md), a calibration bias, not noise.
#include <vector>

namespace twistslam::lidar {

struct DisparityOffsetOptions {
  // samples needed before the median is trusted: with the MAD of ~0.3 px measured on KITTI,
  // 30 samples give a standard error of the median of ~0.07 px.
  int min_samples = 30;
  // px, residuals larger than this are stereo mismatches or wrong LiDAR depths (the offset
  // itself is < 1 px); they are left out of the median and the MAD.
  double max_abs_residual_px = 3.0;
};

struct DisparityOffset {
  bool valid = false;     // false: fewer than min_samples usable pairs (offset_px is then 0)
  double offset_px = 0;   // px, median of fx b / z_lidar - d
  double mad_px = 0;      // px, median absolute deviation from offset_px (unscaled)
  int num_samples = 0;    // pairs used (finite, positive, residual within the gate)
};

// Pairs (disparity d_i = u_left - u_right in px, LiDAR depth z_i in m) with a non-finite or
// non-positive value are skipped (e.g. keypoints without a LiDAR depth carry NaN). Throws
// std::invalid_argument if the sizes differ, fx_baseline (px m) is not finite and positive,
// or the options are out of range.
DisparityOffset estimate_disparity_offset(const std::vector<double>& disparities_px,
                                          const std::vector<double>& lidar_depths_m,
                                          double fx_baseline,
                                          const DisparityOffsetOptions& options = {});

}  // namespace twistslam::lidar
