#pragma once
// From a stereo pair to the frame camera tracking works on: ORB on both images, stereo
// matching along the rows, the class label under each keypoint (a priori dynamic classes are
// kept out of camera tracking, paper eq. 3) and, when a scan is given, LiDAR keypoint depth.
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "features/orb.hpp"
#include "geometry/stereo_camera.hpp"
#include "tracking/frame.hpp"
#include "tracking/object_keypoints.hpp"
#include "tracking/options.hpp"

namespace twistslam::tracking {

struct FrameBuildReport {
  int num_lidar_depth = 0;  // keypoints that took their depth from the scan
  ObjectKeypointReport object_keypoints;  // extra keypoints inside object masks
  std::vector<std::pair<std::string, double>> timings_ms;  // features, stereo[, lidar_depth]
  cv::Mat gray_left, gray_right;  // the 8-bit pair the keypoints came from (may share the input)
};

class FrameBuilder {
 public:
  FrameBuilder(const geometry::StereoCamera& camera, const SlamOptions& options);

  // left / right: CV_8UC1 or CV_8UC3 (RGB) of the camera's size; labels: empty or CV_32SC1
  // class ids per pixel; points_c: N x 3 scan in frame c (empty: none). *frame gets no
  // matches and an identity pose. It is filled in place, not returned: its keypoint grid
  // refers to its own keypoints, which a moved frame would leave behind. object_mask: empty
  // or CV_8UC1, non-zero on object instances (object_class_mask): extra keypoints are
  // extracted there when visual_objects.extra_keypoints (never usable for the camera).
  // instances: empty or the CV_32SC1 instance ids the mask came from (a second pass on the
  // masks left with few keypoints, ObjectKeypointExtractor::extract); support_instances: empty
  // or the ids of every object instance (their own pixels give their edge keypoints' depth).
  // Throws std::invalid_argument on bad sizes or types.
  FrameBuildReport build(int index, double timestamp, const cv::Mat& left, const cv::Mat& right,
                         const cv::Mat& labels, const Points3& points_c, Frame* frame,
                         const cv::Mat& object_mask = cv::Mat(),
                         const cv::Mat& instances = cv::Mat(),
                         const cv::Mat& support_instances = cv::Mat()) const;

  const features::OrbExtractor& extractor() const { return extractor_; }

 private:
  geometry::StereoCamera camera_;
  features::StereoOptions stereo_options_;
  LidarOptions lidar_options_;
  features::OrbExtractor extractor_;
  std::optional<ObjectKeypointExtractor> object_keypoints_;  // when extra_keypoints
  std::unordered_set<int> dynamic_classes_;
};

}  // namespace twistslam::tracking
