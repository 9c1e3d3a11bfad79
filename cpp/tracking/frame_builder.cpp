#include "tracking/frame_builder.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "features/stereo.hpp"

namespace twistslam::tracking {
namespace {

void check_image(const cv::Mat& image, const char* name, const geometry::StereoCamera& cam) {
  if (image.empty()) throw std::invalid_argument(std::string(name) + ": empty image");
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    throw std::invalid_argument(std::string(name) + ": expected 8-bit gray or 3-channel colour");
  if (cam.width > 0 && cam.height > 0 && (image.cols != cam.width || image.rows != cam.height))
    throw std::invalid_argument(std::string(name) + ": image is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + ", the calibration says " +
                                std::to_string(cam.width) + "x" + std::to_string(cam.height));
}

// 0 on a priori dynamic classes, 255 elsewhere: their LiDAR returns are never used (eq. 3).
cv::Mat static_class_mask(const cv::Mat& labels, const std::unordered_set<int>& dynamic_classes) {
  cv::Mat mask(labels.size(), CV_8UC1);
  for (int v = 0; v < labels.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    std::uint8_t* m = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < labels.cols; ++u) m[u] = dynamic_classes.count(l[u]) ? 0 : 255;
  }
  return mask;
}

}  // namespace

FrameBuilder::FrameBuilder(const geometry::StereoCamera& camera, const SlamOptions& options)
    : camera_(camera), stereo_options_(options.stereo), lidar_options_(options.lidar),
      extractor_(options.orb),
      dynamic_classes_(options.tracking.dynamic_class_ids.begin(), options.tracking.dynamic_class_ids.end()) {
  if (options.visual_objects.enabled && options.visual_objects.extra_keypoints &&
      options.visual_objects.extra_keypoints_max > 0)
    object_keypoints_.emplace(options.orb, options.visual_objects);
}

FrameBuildReport FrameBuilder::build(int index, double timestamp, const cv::Mat& left,
                                     const cv::Mat& right, const cv::Mat& labels,
                                     const Points3& points_c, Frame* out_frame,
                                     const cv::Mat& object_mask, const cv::Mat& instances,
                                     const cv::Mat& support_instances) const {
  check_image(left, "image_left", camera_);
  check_image(right, "image_right", camera_);
  if (left.size() != right.size()) throw std::invalid_argument("image_right: size differs from image_left");
  if (!labels.empty() && (labels.type() != CV_32SC1 || labels.size() != left.size()))
    throw std::invalid_argument("labels: expected int32 class ids of the image size");
  if (!object_mask.empty() && (object_mask.type() != CV_8UC1 || object_mask.size() != left.size()))
    throw std::invalid_argument("object_mask: expected uint8 of the image size");

  FrameBuildReport out;
  const cv::Mat gray_left = features::to_gray(left, /*rgb=*/true),
                gray_right = features::to_gray(right, /*rgb=*/true);
  out.gray_left = gray_left;
  out.gray_right = gray_right;
  // Left and right pyramids are extracted on both cores, then matched along the rows.
  features::StereoFeatures stereo_features =
      features::extract_and_match(extractor_, gray_left, gray_right, camera_, stereo_options_);
  out.timings_ms.emplace_back("features", stereo_features.extract_ms);
  out.timings_ms.emplace_back("stereo", stereo_features.match_ms);
  const size_t num_main = stereo_features.left.size();
  if (object_keypoints_ && !object_mask.empty()) {
    const auto start = std::chrono::steady_clock::now();
    out.object_keypoints = object_keypoints_->extract(gray_left, object_mask, camera_, &stereo_features,
                                                       instances, support_instances);
    out.timings_ms.emplace_back(
        "object_keypoints",
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  const features::Keypoints& kp_left = stereo_features.left;
  const features::StereoMatches& stereo = stereo_features.matches;

  Frame& frame = *out_frame;
  frame = Frame();
  frame.index = index;
  frame.timestamp = timestamp;
  map::StereoKeypoints& k = frame.keypoints;
  const size_t n = kp_left.keypoints.size();
  k.uv.resize(n), k.octave.resize(n), k.u_right.resize(n), k.depth.resize(n);
  k.descriptors.resize(n), k.label.assign(n, -1);
  frame.usable.assign(n, 1);
  for (size_t i = 0; i < n; ++i) {
    const cv::KeyPoint& kp = kp_left.keypoints[i];
    k.uv[i] = Vec2(kp.pt.x, kp.pt.y);
    k.octave[i] = kp.octave;
    k.u_right[i] = stereo.u_right[i];
    k.depth[i] = stereo.depth[i];
    std::memcpy(k.descriptors[i].data(), kp_left.descriptors.ptr<std::uint8_t>(static_cast<int>(i)), 32);
    if (!labels.empty()) {
      const int u = std::clamp(static_cast<int>(std::lround(kp.pt.x)), 0, labels.cols - 1);
      const int v = std::clamp(static_cast<int>(std::lround(kp.pt.y)), 0, labels.rows - 1);
      k.label[i] = labels.at<int>(v, u);
      frame.usable[i] = !dynamic_classes_.count(k.label[i]);  // eq. 3: static clusters only
    }
    if (i >= num_main) frame.usable[i] = 0;  // extra keypoints lie on objects
  }
  if (lidar_options_.use_depth && points_c.rows() > 0) {
    const auto start = std::chrono::steady_clock::now();
    const cv::Mat static_mask = !labels.empty() && !dynamic_classes_.empty()
                                    ? static_class_mask(labels, dynamic_classes_)
                                    : cv::Mat();
    const LidarDepthStats stats =
        apply_lidar_depth(points_c, camera_, lidar_options_, static_mask, frame.usable, k);
    out.num_lidar_depth = stats.num_replaced + stats.num_added;
    out.timings_ms.emplace_back(
        "lidar_depth",
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  frame.clear_matches();
  frame.grid.build(frame.keypoints.uv, left.cols, left.rows);
  return out;
}

}  // namespace twistslam::tracking
