#pragma once
// Thresholds of the LiDAR depth association (docs/lidar.md). Values measured on KITTI 0001
// frames 0-26 (HDL-64 projected into the 1242 x 375 colour camera, fx = 721 px).

namespace twistslam::lidar {

struct LidarDepthOptions {
  // px, side of the square pixel buckets of the scan projection; >= search_radius_px keeps a
  // query to at most 3 x 3 buckets.
  double cell_size_px = 8.0;
  // px, returns this close to a keypoint are its neighbourhood. The HDL-64's lines are 4.2 px
  // (upper block, 1/3 deg) to 6.3 px (lower block, 1/2 deg) apart in the KITTI image, returns
  // ~2.2 px apart along a line (0.18 deg at 10 Hz), so 6 px brackets a keypoint by two lines.
  // Measured on 0001 (27 frames): 4 px gives 6.9k depths, 6 px 17.4k, 8 px 20.3k with twice
  // the poor fits; the stereo/LiDAR agreement is the same for all three.
  double search_radius_px = 6.0;
  // m, returns nearer than this along the left optical axis are dropped (nothing the camera
  // matches lies closer; it removes points behind or at the image plane).
  double min_depth_m = 1.0;
  // m, returns farther than this are dropped (the HDL-64's rated range is 120 m).
  double max_depth_m = 120.0;
  // returns needed for a plane fit: 3 parameters plus one left to measure the residual.
  int min_returns = 4;
  // relative depth, RMS residual of the local fit (|z_i - z_fit| / z_fit) above which the
  // neighbourhood is not one plane: 2 % is ~10x the HDL-64's 2 cm noise at 10 m, while a
  // box edge (near and far layers in one fit) gives far more. On 0001, 1 % / 4 % change the
  // accepted depths by -8 % / +5 % and the stereo/LiDAR band ratios by < 0.1 %.
  double max_fit_residual = 0.02;
  // relative depth, gap between consecutive sorted depths that separates a near layer from a
  // far one (z_far > z_near * (1 + gap)) when the single-plane fit failed. Road scan lines at
  // 30 m are ~12 % apart, but the road passes the single-plane fit first. On 0001, 5 % / 20 %
  // move < 1 % of the depths.
  double layer_gap = 0.1;
};

// Throws std::invalid_argument naming the first option that is non-finite or out of range.
void validate(const LidarDepthOptions& options);

}  // namespace twistslam::lidar
