#pragma once
// Extra keypoints inside object masks (paper, "Clusters creation": small and far objects keep
// enough points). The frame's ORB budget is spread over the whole image, so a car at 40 m
// (~40 x 30 px) gets a handful of corners and the stereo matcher finds a partner for few of
// them. Here a second, denser ORB pass runs inside the instance masks of the object classes,
// and every object keypoint without depth (new or from the main pass) gets one from a SAD
// scan along the row (features/stereo_search.hpp).
#include <opencv2/core/mat.hpp>

#include <vector>

#include "features/orb.hpp"
#include "features/stereo.hpp"
#include "features/stereo_search.hpp"
#include "geometry/stereo_camera.hpp"
#include "tracking/object_tracking_options.hpp"

namespace twistslam::tracking {

struct ObjectKeypointReport {
  int num_added = 0;      // new keypoints appended to the left keypoints
  int num_deprived = 0;   // instances that got a second pass on their own mask
  int num_new_depth = 0;  // object keypoints (new or old) that the SAD scan gave a depth
  int num_left_right_removed = 0;  // object keypoints whose depth failed the left-right check
  int num_instance_rescanned = 0;  // edge keypoints whose depth was searched on their instance
  int num_instance_dropped = 0;    // ... and found none there
  int num_pulled_nearer_dropped = 0;  // far vehicle keypoints a nearer occluder pulled (dropped)
  int num_right_occluded_dropped = 0;  // vehicle keypoints a nearer vehicle hides from the right camera
};

// CV_8UC1 mask, 255 on pixels of an instance (instances > 0) whose class (labels; any class
// when labels is empty) is in object_class_ids. Both CV_32SC1 of one size.
cv::Mat object_class_mask(const cv::Mat& instances, const cv::Mat& labels,
                          const std::vector<int>& object_class_ids);

// The instance ids (CV_32SC1) of the pixels object_class_mask keeps for class_ids, 0 elsewhere:
// the instances a second pass may serve (the vehicles).
cv::Mat instances_of_classes(const cv::Mat& instances, const cv::Mat& labels,
                             const std::vector<int>& class_ids);

// Sets ids (CV_32SC1) to kOccluderId where labels (CV_32SC1, one size) hold one of class_ids
// and ids hold no instance (<= 0): the thin things (poles, tree trunks) that stand in front of
// far cars, for the pulled-nearer check; negative ids count as no instance elsewhere.
inline constexpr int kOccluderId = -2;
void mark_occluder_classes(const cv::Mat& labels, const std::vector<int>& class_ids, cv::Mat* ids);

// The SAD scan's options for object pixels (extra keypoints, flow-located points): the object
// depth range and the extra keypoints' cost and uniqueness bounds.
features::StereoSearchOptions object_stereo_search(const ObjectTrackingOptions& options);

class ObjectKeypointExtractor {
 public:
  // main: the frame's ORB options (scale factor and levels are shared, so octaves agree).
  ObjectKeypointExtractor(const features::OrbOptions& main, const ObjectTrackingOptions& options);

  // Appends to features->left (keypoints, descriptors) and features->matches the object
  // keypoints farther than min spacing from every existing left keypoint, then searches the
  // depth of every object keypoint that has none; with instances and instance_pixel_stereo, an
  // object keypoint whose SAD window also covers other pixels is matched again on its
  // instance's pixels only (support_instances: the ids of every object instance, CV_32SC1 of
  // the image size; empty: off); with the left-right check, every object keypoint's depth is then
  // checked back from the right image. Needs the left and right
  // pyramids of extract_and_match. Keypoints at index >= the old size are the new ones.
  // instances (empty, or CV_32SC1 ids of the image size; <= 0: none): an instance whose mask
  // then holds fewer than extra_min_instance_keypoints keypoints gets a second pass on its own
  // mask, when it covers at least extra_min_instance_area_px pixels; with pulled_nearer_check,
  // those instances' far keypoints that a nearer occluder pulled lose their depth
  // (features::drop_matches_pulled_nearer); with right_occlusion_check, those instances'
  // keypoints that a nearer one hides from the right camera lose theirs
  // (features::drop_matches_occluded_in_right).
  ObjectKeypointReport extract(const cv::Mat& gray_left, const cv::Mat& object_mask,
                               const geometry::StereoCamera& camera,
                               features::StereoFeatures* features,
                               const cv::Mat& instances = cv::Mat(),
                               const cv::Mat& support_instances = cv::Mat()) const;

 private:
  features::OrbExtractor extractor_;
  int min_instance_keypoints_;
  int min_instance_area_px_;
  features::StereoSearchOptions search_;
  double min_spacing_px_;
  bool left_right_check_;
  float left_right_tolerance_px_;
  bool instance_pixel_stereo_;
  float instance_pixel_min_fraction_;
  bool pulled_nearer_check_;
  float pulled_nearer_min_depth_m_;
  float pulled_nearer_max_px_;
  bool right_occlusion_check_;
  float right_occlusion_margin_px_;
  int right_occlusion_min_keypoints_;
};

}  // namespace twistslam::tracking
