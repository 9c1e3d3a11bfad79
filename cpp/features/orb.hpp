#pragma once
// ORB features spread over the whole image: a scale pyramid, FAST corners found per grid cell
// (with a lower threshold in cells where the normal one finds nothing), a quadtree that keeps
// the strongest corner of each of N evenly sized regions per level, intensity-centroid
// orientation and rotated-BRIEF descriptors (OpenCV's learned 256-test pattern, computed
// through cv::ORB::compute on our own pyramid levels). See docs/features.md.
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include <cstdint>
#include <vector>

#include "features/hamming.hpp"  // descriptor_distance of two raw descriptors

namespace twistslam::features {

// Pixels of a level image kept free of keypoints at each border: the rotated 31x31 BRIEF patch
// reaches ~22 px from its centre and the intensity-centroid circle 15 px.
inline constexpr int kEdgeBorder = 19;
// Side of the (unrotated) BRIEF patch and diameter of the orientation circle, level pixels.
inline constexpr int kPatchSize = 31;

struct OrbOptions {
  // Keypoints per (left) image. 2000 on KITTI's 1242x375 gives one corner per ~15x15 px, what
  // ORB-SLAM2 uses for stereo KITTI: enough for tracking after dynamic objects are masked.
  int num_features = 2000;
  // Ratio between consecutive pyramid levels (> 1). 1.2 keeps the scale change between
  // levels below what the BRIEF tests tolerate, so a corner seen at a new distance is found
  // on a neighbouring level with a similar descriptor.
  float scale_factor = 1.2f;
  // Pyramid levels. 8 levels of 1.2 cover a 3.6x change of scale (e.g. a car from 10 to 36 m).
  // 4 levels (1.2^3 = 1.7x scale range) rather than ORB-SLAM2's 8: consecutive frames and
  // keyframes 2 frames apart see little scale change, and the coarse levels' keypoints are
  // localised to +-2 px at level 0 (simulator, urban: rotation RPE 0.0176 -> 0.0147 deg/frame).
  int num_levels = 4;
  // FAST intensity threshold (grey levels). 20 is the usual ORB value: stable corners on
  // natural images without picking up sensor noise.
  int fast_threshold = 20;
  // Threshold retried in grid cells where fast_threshold finds nothing (grey levels). 7 still
  // finds corners on low-contrast road and shadows, so every cell can contribute.
  int min_fast_threshold = 7;
  // Side of the bucketing grid cell (level pixels). 35 px gives ~400 cells at level 0 on KITTI:
  // small enough to cover the image, large enough for the 7-px FAST retry to find a corner.
  int cell_size = 35;
};

// Every option with its valid range (inclusive, the field's unit), for the checks of
// OrbExtractor and the Python bindings (options/option_range.hpp). The upper bounds are far
// beyond any useful value; they keep the per-level shares and the stereo matcher's right-image
// count (x right_features_factor <= 16) inside int.
template <typename Visit>
void for_each_option(OrbOptions& o, Visit&& visit) {
  // 0 = pyramid only; 1e5 is one keypoint per ~5 px^2 of a KITTI image, more than FAST finds
  visit("num_features", o.num_features, 0, 100000);
  // 1.001: a ratio of 1 makes identical levels (and a zero sum of level shares); 4: a level a
  // quarter the size of the previous one leaves scales no BRIEF descriptor bridges
  visit("scale_factor", o.scale_factor, 1.001, 4.0);
  // 32 levels of even 1.001 exceed nothing; of 1.2 they reach a 285x scale change
  visit("num_levels", o.num_levels, 1, 32);
  // grey levels of an 8-bit image: FAST compares against pixel +- threshold
  visit("fast_threshold", o.fast_threshold, 1, 254);
  visit("min_fast_threshold", o.min_fast_threshold, 1, 254);
  // 8 px: FAST's 3-px ring leaves a smaller cell no room for a corner; 4096 px is one cell
  // over any camera image (no bucketing)
  visit("cell_size", o.cell_size, 8, 4096);
}

// Throws std::invalid_argument naming the option ("OrbOptions: num_levels = 0 is out of range
// [1, 32]") for a value outside for_each_option's range or min_fast_threshold >
// fast_threshold.
void check_options(const OrbOptions& options);

// Keypoints and descriptors of one image, one entry per keypoint (level order, coarse last).
struct Keypoints {
  // Level-0 pixel coordinates (pixel centres at integers), octave = pyramid level,
  // angle in degrees [0, 360), response = FAST score, size = 31 * scale of the level.
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  // N x 32 CV_8U, row i describes keypoints[i]
  // The pyramid the keypoints were found on (level 0 is the input image, shared). Kept so that
  // match_stereo and later modules reuse it; may be cleared, it is rebuilt when missing.
  std::vector<cv::Mat> pyramid;
  float scale_factor = 1.2f;  // the extractor's scale_factor (to rebuild the pyramid)

  std::size_t size() const { return keypoints.size(); }
  bool empty() const { return keypoints.empty(); }
};

// Image pyramid: level l has size round(W / s^l) x round(H / s^l), each level resized
// (bilinear) from the previous one. Levels too small to hold a keypoint are not built.
// A level-l pixel x maps to level 0 as (x + 0.5) * (W / W_l) - 0.5 (exact per axis).
std::vector<cv::Mat> build_pyramid(const cv::Mat& gray, float scale_factor, int num_levels);

// Level-0 coordinate of a level pixel and back, using the exact size ratio of the level.
inline cv::Point2f level_to_image(const cv::Point2f& p, const cv::Size& level0,
                                  const cv::Size& level) {
  const float sx = static_cast<float>(level0.width) / level.width;
  const float sy = static_cast<float>(level0.height) / level.height;
  return {(p.x + 0.5f) * sx - 0.5f, (p.y + 0.5f) * sy - 0.5f};
}
inline cv::Point2f image_to_level(const cv::Point2f& p, const cv::Size& level0,
                                  const cv::Size& level) {
  const float sx = static_cast<float>(level.width) / level0.width;
  const float sy = static_cast<float>(level.height) / level0.height;
  return {(p.x + 0.5f) * sx - 0.5f, (p.y + 0.5f) * sy - 0.5f};
}

class OrbExtractor {
 public:
  // Throws std::invalid_argument on invalid options (scale_factor <= 1, num_levels < 1, ...).
  explicit OrbExtractor(const OrbOptions& options = {});

  // Keypoints of an 8-bit grey image (CV_8UC1; see to_gray). mask: optional CV_8UC1 of the same
  // size, 0 where no keypoint may lie (e.g. a priori dynamic classes). Thread-safe (const, no
  // shared state): the left and right images may be processed concurrently.
  // Throws std::invalid_argument on an empty or non-CV_8UC1 image or a mismatched mask.
  Keypoints extract(const cv::Mat& gray, const cv::Mat& mask = {}) const;
  // The same on a pyramid of the image already built (build_pyramid with this extractor's
  // scale_factor, e.g. another extractor's Keypoints::pyramid of the same image): its first
  // num_levels levels are shared, not rebuilt, and the result is identical to extract() on
  // its level 0. Throws std::invalid_argument for an empty pyramid or a level that is missing
  // or not of this scale_factor's size.
  Keypoints extract_on_pyramid(const std::vector<cv::Mat>& pyramid, const cv::Mat& mask = {}) const;

  const OrbOptions& options() const { return options_; }
  // s^l, 1 / s^l, s^(2l) (variance of a level-l keypoint position in level-0 px^2), inverse.
  const std::vector<float>& scale_factors() const { return scale_; }
  const std::vector<float>& inv_scale_factors() const { return inv_scale_; }
  const std::vector<float>& level_sigma2() const { return sigma2_; }
  const std::vector<float>& inv_level_sigma2() const { return inv_sigma2_; }
  // Keypoints wanted on each level (geometric in 1/s, summing to num_features).
  const std::vector<int>& features_per_level() const { return per_level_; }

 private:
  Keypoints extract_levels(std::vector<cv::Mat> pyramid, const cv::Mat& mask) const;

  OrbOptions options_;
  std::vector<float> scale_, inv_scale_, sigma2_, inv_sigma2_;
  std::vector<int> per_level_;
  std::vector<int> circle_half_width_;  // orientation circle: half width of each row
};

// 8-bit grey version of an image: CV_8UC1 is returned as is (shared, no copy); CV_8UC3 is BGR
// (OpenCV's order) or RGB when rgb = true; CV_8UC4 is BGRA / RGBA. Throws std::invalid_argument
// for other types and for empty images.
cv::Mat to_gray(const cv::Mat& bgr_or_gray, bool rgb = false);

// Hamming distance of two descriptor rows (1 x 32 CV_8U, e.g. descriptors.row(i)).
// Throws std::invalid_argument if either is not 32 bytes of CV_8U.
int descriptor_distance(const cv::Mat& a, const cv::Mat& b);

}  // namespace twistslam::features
