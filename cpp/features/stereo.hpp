#pragma once
// Stereo matching of ORB keypoints along the rows of a rectified pair: for each left keypoint,
// the right keypoints on nearby rows, at a neighbouring octave and inside the disparity range
// of [min_depth, max_depth] are compared by Hamming distance; the best one is refined to
// sub-pixel by a zero-mean SAD search on the keypoint's pyramid level (right rows sampled at
// the vertical offset the camera pair predicts, minimum located by a V fit), and matches whose
// SAD is far above the frame's median are dropped. See docs/features.md.
#include <opencv2/core.hpp>

#include <vector>

#include "features/orb.hpp"
#include "geometry/stereo_camera.hpp"

namespace twistslam::features {

struct StereoOptions {
  // Largest Hamming distance (bits of 256) of a descriptor match. 75 is half-way between the
  // strict (50) and loose (100) thresholds of ORB-SLAM-style matchers: the two views of a
  // 0.5 m baseline differ little, and the SAD check below removes what slips through.
  int max_hamming = 75;
  // Half height of the row band searched in the right image (level-0 px, times the scale of
  // the keypoint's level). 2 px absorbs the 1-px localisation of FAST at coarse levels and the
  // sub-pixel vertical offset of KITTI's rectified cameras 2 and 3 (~2 px m / depth).
  float row_radius = 2.0f;
  // Right candidates must lie within this many octaves of the left keypoint (the two images
  // see a surface at almost the same scale).
  int octave_tolerance = 1;
  // Half width / half height of the SAD window (level px): 15 x 5. A window flatter than
  // ORB-SLAM's 11 x 11 keeps sub-pixel accuracy on surfaces slanted in depth: on a rendered
  // road the disparity changes by 0.32 px per row, which an 11-row window smears over +-1.6 px
  // (median error 0.29 px there, against 0.16 px for 15 x 5; fronto-parallel planes: 0.03 px
  // with either).
  int patch_radius = 7;
  int patch_half_height = 2;
  // Half range of the SAD search around the descriptor match (level px). The match is good to
  // ~1 px of its level, 5 px leaves room to reject minima on the border of the range.
  int refine_range = 5;
  // Closest depth kept (m). 0.5 m is the closest a KITTI car camera sees (the bonnet); it also
  // bounds the disparity search to fx * b / 0.5 (~770 px on KITTI).
  float min_depth = 0.5f;
  // Farthest depth kept (m). On KITTI (fx b ~ 385 px m) 80 m is a 4.8 px disparity, where a
  // 0.25 px matching error is already 5 % of the depth (~150 baselines); farther points carry
  // no depth worth using and are left to monocular tracking.
  float max_depth = 80.0f;
  // Matches whose normalised SAD exceeds outlier_factor times the median are dropped. 2.1 =
  // 1.5 x 1.4, i.e. ~1.5 robust standard deviations above a half-normal median.
  float outlier_factor = 2.1f;
  // extract_and_match only: the right image gets right_features_factor x num_features
  // keypoints. They only serve as match candidates, and a denser set makes it likelier that
  // the partner of a left corner survived the bucketing (on rendered KITTI-like pairs 2x
  // raises the match rate from ~63 % to ~77 % of the left keypoints, for ~2 ms).
  float right_features_factor = 2.0f;
};

// One entry per left keypoint; -1 where unmatched.
struct StereoMatches {
  std::vector<float> u_right;  // level-0 column of the match in the right image (px)
  std::vector<float> depth;    // depth along the left camera's optical axis (m): fx b / (u_l - u_r)
  std::size_t num_matched() const;
};

// Throws std::invalid_argument if the images are empty, of different sizes or not CV_8UC1, if
// the keypoint and descriptor counts disagree, or if the camera has no positive baseline.
// Uses left.pyramid / right.pyramid when they match the images, otherwise rebuilds them.
StereoMatches match_stereo(const Keypoints& left, const Keypoints& right,
                           const cv::Mat& gray_left, const cv::Mat& gray_right,
                           const geometry::StereoCamera& camera,
                           const StereoOptions& options = {});

// Everything a tracker needs from one stereo frame.
struct StereoFeatures {
  Keypoints left, right;
  StereoMatches matches;
  double extract_ms = 0, match_ms = 0;  // wall time of the two stages
};

// Extracts the left and right images in parallel (two threads), then matches them.
// mask_left: optional CV_8UC1, 0 = no left keypoint there (the right image is not masked:
// its keypoints only serve as match candidates).
StereoFeatures extract_and_match(const OrbExtractor& extractor, const cv::Mat& gray_left,
                                 const cv::Mat& gray_right, const geometry::StereoCamera& camera,
                                 const StereoOptions& options = {},
                                 const cv::Mat& mask_left = {});

}  // namespace twistslam::features
