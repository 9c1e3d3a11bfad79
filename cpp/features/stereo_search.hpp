#pragma once
// Stereo depth for left keypoints that have no right keypoint to match: a zero-mean SAD scan
// along the row over the whole disparity range on the keypoint's pyramid level, kept when the
// minimum is distinct (uniqueness against the second-best minimum) and its normalised cost
// low, then refined to sub-pixel like the descriptor matches (features/sad.hpp).
// Small and far objects are where this matters: a car at 40 m covers ~40 x 30 px, where the
// right image's bucketed keypoints rarely hold the partner of a left corner (paper: extra
// keypoints keep small objects tracked).
#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

#include "features/orb.hpp"
#include "features/stereo.hpp"
#include "geometry/stereo_camera.hpp"

namespace twistslam::features {

struct StereoSearchOptions {
  float min_depth = 1.5f;   // m: closest depth searched (fx b / 1.5 ~ 257 px on KITTI)
  float max_depth = 60.0f;  // m: farthest (object points beyond are not used)
  // Normalised zero-mean SAD (SAD / left window contrast) above which no depth is given.
  float max_cost = 0.7f;
  // The best cost must be below uniqueness x the best cost >= 2 px away from it.
  float uniqueness = 0.7f;
  int patch_radius = 7;       // half width of the SAD window (level px), as StereoOptions
  int patch_half_height = 2;  // half height (level px)
};

// Throws std::invalid_argument naming the bad option.
void check_options(const StereoSearchOptions& options);

// Fills matches->u_right / depth of left keypoint i for every i in `which` that the scan
// accepts (others keep their value). pyramid_left / pyramid_right: the images' pyramids with
// at least the keypoints' octaves (Keypoints::pyramid of the left and right extraction).
// Returns how many got a depth. Throws std::invalid_argument on bad sizes or indices.
int search_stereo(const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
                  const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
                  const StereoSearchOptions& options, const std::vector<int>& which,
                  StereoMatches* matches);

// The depth of one level-0 pixel that is no keypoint (a point located by the optical flow):
// the scan of search_stereo on the level-0 images left / right (CV_8UC1, one size) at (u, v),
// on the window pixels `support` marks (row-major (2 patch_half_height + 1) x
// (2 patch_radius + 1), 1 = used; nullptr: all). Returns false (outputs untouched) when the
// scan is rejected or the window leaves the image. Throws std::invalid_argument on bad images.
bool search_pixel_stereo(const cv::Mat& left, const cv::Mat& right,
                         const geometry::StereoCamera& camera, const StereoSearchOptions& options,
                         float u, float v, const std::uint8_t* support, float* u_right,
                         float* depth);

// What depth_on_instance_pixels did.
struct InstanceSupportReport {
  int num_rescanned = 0;  // keypoints whose window also covered other pixels, scanned again
  int num_dropped = 0;    // of those, the ones the scan on their object's pixels rejected
};

// Depth of object keypoints from their own object's pixels. A keypoint on an object's edge has a
// SAD window that also covers the background (or another object), whose texture can outweigh
// the object's: urban seed 4's pedestrian, 12 px wide beside a nearer tree trunk, took the
// trunk's disparity (1.5-3 m short). For each keypoint of `which` with a depth, on an instance
// (`instances`: CV_32SC1 ids at the level-0 size, 0 = no instance), whose window covers pixels
// of other ids, the window's pixels on its instance (at least min_support_fraction of it) are
// scanned again over the whole disparity range (sad.hpp's support, as search_stereo otherwise);
// the keypoint gets that depth, or none when the scan is rejected. Windows wholly on their
// instance keep their depth, as do those with too small a share of it. Throws
// std::invalid_argument as search_stereo, or on a bad instance image or fraction.
InstanceSupportReport depth_on_instance_pixels(
    const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
    const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
    const StereoSearchOptions& options, const std::vector<int>& which, const cv::Mat& instances,
    float min_support_fraction, StereoMatches* matches);

// Object keypoints whose match a nearer object's pixels in the window pulled nearer. A far car
// seen between nearer cars: its edge keypoints' windows hold the nearer car's texture, which
// outweighs its own, and they take (or lean towards) its disparity (urban seed 12: a parked car
// at 46-50 m tracked 1.4 m short). For each keypoint of `which` with a depth of at least
// min_depth (m), on an instance (`instances` as depth_on_instance_pixels), whose window also
// covers another instance (and at least min_support_fraction of it its own), the instance's
// own pixels are scanned again; when their disparity is smaller than the match's by more than
// max_pull_px (level-0 px), the match loses its depth. A rejected own-pixel scan keeps the
// match, as do windows beside no other instance (a lead car's outline against the road and
// buildings is what makes its windows distinctive). Reports the keypoints scanned again and
// those dropped. Throws std::invalid_argument as depth_on_instance_pixels, or on a negative
// max_pull_px.
InstanceSupportReport drop_matches_pulled_nearer(
    const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
    const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
    const StereoSearchOptions& options, const std::vector<int>& which, const cv::Mat& instances,
    float min_support_fraction, float min_depth, float max_pull_px, StereoMatches* matches);

// Left-right consistency of existing matches: the right window at each match of `which`,
// scanned along the left row over the disparity range, must find its best match back within
// tolerance_px (level px) of the left keypoint. A point the right camera does not see (an
// object in front of it there: the cameras are 0.54 m apart) was matched to the occluder's
// texture, and the occluder's window finds itself farther right in the left image. Failing
// matches get u_right = depth = -1; matches whose windows leave the image are kept. Returns
// how many were removed. Throws std::invalid_argument as search_stereo.
int check_left_right(const Keypoints& left, const std::vector<cv::Mat>& pyramid_left,
                     const std::vector<cv::Mat>& pyramid_right, const geometry::StereoCamera& camera,
                     const StereoSearchOptions& options, const std::vector<int>& which,
                     float tolerance_px, StereoMatches* matches);

}  // namespace twistslam::features
