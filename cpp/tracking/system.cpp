#include "tracking/system.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cmath>
#include <stdexcept>

#include "features/stereo.hpp"

namespace twistslam::tracking {
namespace {

class StageTimer {
 public:
  explicit StageTimer(TrackResult* r) : result_(r), start_(std::chrono::steady_clock::now()) {}
  void lap(const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    result_->timings_ms.emplace_back(stage, std::chrono::duration<double, std::milli>(now - start_).count());
    start_ = now;
  }

 private:
  TrackResult* result_;
  std::chrono::steady_clock::time_point start_;
};

void check_image(const cv::Mat& image, const char* name, const geometry::StereoCamera& cam) {
  if (image.empty()) throw std::invalid_argument(std::string(name) + ": empty image");
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    throw std::invalid_argument(std::string(name) + ": expected 8-bit gray or 3-channel colour");
  if (cam.width > 0 && cam.height > 0 && (image.cols != cam.width || image.rows != cam.height))
    throw std::invalid_argument(std::string(name) + ": image is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + ", the calibration says " +
                                std::to_string(cam.width) + "x" + std::to_string(cam.height));
}

}  // namespace

const char* to_string(Status status) {
  switch (status) {
    case Status::kInitialized: return "initialized";
    case Status::kOk: return "ok";
    case Status::kLost: return "lost";
    case Status::kRelocalized: return "relocalized";
  }
  return "unknown";
}

System::System(const geometry::StereoCamera& camera, const SlamOptions& options)
    : camera_(camera), options_(options), extractor_(options.orb) {
  for (float s2 : extractor_.level_sigma2()) inv_level_sigma2_.push_back(1.0 / s2);
  dynamic_classes_.insert(options.tracking.dynamic_class_ids.begin(), options.tracking.dynamic_class_ids.end());
}

void System::reset() {
  map_.clear();
  state_ = State::kEmpty;
  has_last_ = false;
  velocity_ = Mat4::Identity();
  has_velocity_ = false;
  reference_keyframe_ = last_keyframe_frame_ = segment_first_keyframe_ = -1;
  segment_ = -1;
  recent_points_.clear();
  local_keyframes_.clear();
  trajectory_.clear();
}

Frame System::build_frame(int index, double timestamp, const cv::Mat& left, const cv::Mat& right,
                          const cv::Mat& labels, const Points3& points_c, TrackResult* result) {
  check_image(left, "image_left", camera_);
  check_image(right, "image_right", camera_);
  if (left.size() != right.size()) throw std::invalid_argument("image_right: size differs from image_left");
  if (!labels.empty() && (labels.type() != CV_32SC1 || labels.size() != left.size()))
    throw std::invalid_argument("labels: expected int32 class ids of the image size");

  const cv::Mat gray_left = features::to_gray(left, /*rgb=*/true),
                gray_right = features::to_gray(right, /*rgb=*/true);
  // Left and right pyramids are extracted on both cores, then matched along the rows.
  const features::StereoFeatures stereo_features =
      features::extract_and_match(extractor_, gray_left, gray_right, camera_, options_.stereo);
  result->timings_ms.emplace_back("features", stereo_features.extract_ms);
  result->timings_ms.emplace_back("stereo", stereo_features.match_ms);
  const features::Keypoints& kp_left = stereo_features.left;
  const features::StereoMatches& stereo = stereo_features.matches;

  Frame frame;
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
  }
  if (options_.lidar.use_depth && points_c.rows() > 0) {
    const auto start = std::chrono::steady_clock::now();
    cv::Mat static_mask;  // 0 on a-priori dynamic classes: their returns are never used
    if (!labels.empty() && !dynamic_classes_.empty()) {
      static_mask.create(labels.size(), CV_8UC1);
      for (int v = 0; v < labels.rows; ++v) {
        const int* l = labels.ptr<int>(v);
        std::uint8_t* m = static_mask.ptr<std::uint8_t>(v);
        for (int u = 0; u < labels.cols; ++u) m[u] = dynamic_classes_.count(l[u]) ? 0 : 255;
      }
    }
    const LidarDepthStats stats =
        apply_lidar_depth(points_c, camera_, options_.lidar, static_mask, frame.usable, k);
    lidar_depth_keypoints_ = stats.num_replaced + stats.num_added;
    result->timings_ms.emplace_back(
        "lidar_depth",
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  frame.clear_matches();
  frame.grid.build(frame.keypoints.uv, left.cols, left.rows);
  return frame;
}

Mat4 System::predicted_pose() const {
  if (!has_last_) return Mat4::Identity();
  return velocity_ * last_frame_.T_c_w;  // constant velocity
}

TrackResult System::track(int index, double timestamp, const cv::Mat& left, const cv::Mat& right,
                          const cv::Mat& labels, const Points3& points_c) {
  TrackResult result;
  lidar_depth_keypoints_ = 0;
  Frame frame = build_frame(index, timestamp, left, right, labels, points_c, &result);
  result.num_lidar_depth = lidar_depth_keypoints_;
  StageTimer timer(&result);
  frame.T_c_w = predicted_pose();
  bool tracked = false;

  if (state_ == State::kTracking || state_ == State::kLost) {
    // Without a velocity (the frame after a map start) the prediction is "no motion", off by a
    // whole frame of driving: search four times as wide.
    // After a loss the last frame has no matches: relocalise in the last local map instead.
    tracked = state_ == State::kLost ? relocalize_in_local_map(frame)
                                     : track_with_motion_model(frame, has_velocity_ ? 1.0 : 4.0);
    // The motion model lost its matches (an unexpected motion): try the local map before
    // giving up on this map.
    if (!tracked && state_ == State::kTracking) tracked = relocalize_in_local_map(frame);
    timer.lap("track_motion");
    if (tracked) tracked = track_local_map(frame);
    timer.lap("track_local_map");
    if (tracked) {
      result.status = state_ == State::kLost ? Status::kRelocalized : Status::kOk;
    }
  }
  if (!tracked) {
    const bool fresh = state_ == State::kEmpty;
    frame.T_c_w = predicted_pose();
    frame.clear_matches();
    if (count_initial_points(frame) >= options_.tracking.min_init_points) {
      start_segment(frame);  // the first frame, or a restart after tracking loss
      result.status = fresh ? Status::kInitialized : Status::kRelocalized;
      result.is_keyframe = true;
      tracked = true;
    } else {
      result.status = Status::kLost;
    }
  }

  if (tracked) {
    if (has_last_ && state_ == State::kTracking && !result.is_keyframe) {
      velocity_ = frame.T_c_w * geometry::se3_inverse(last_frame_.T_c_w);
      has_velocity_ = true;
    }
    state_ = State::kTracking;
    last_ba_ms_ = 0;
    if (!result.is_keyframe && need_keyframe(frame)) {
      insert_keyframe(frame);
      result.is_keyframe = true;
    }
    timer.lap("keyframe");
    if (last_ba_ms_ > 0) {  // report the BA apart from the rest of the keyframe insertion
      result.timings_ms.back().second -= last_ba_ms_;
      result.timings_ms.emplace_back("local_ba", last_ba_ms_);
    }
  } else if (state_ != State::kEmpty) {
    state_ = State::kLost;  // keep the velocity: the next prediction continues the motion
  }

  // Trajectory entry relative to the reference keyframe (BA corrections reach it later).
  TrajectoryEntry entry{index, timestamp, reference_keyframe_, frame.T_c_w, result.status};
  if (reference_keyframe_ >= 0) entry.T_c_r = frame.T_c_w * map_.keyframe(reference_keyframe_).T_w_c();
  trajectory_.push_back(entry);

  result.T_w_c = geometry::se3_inverse(frame.T_c_w);
  result.num_inliers = frame.num_matched_inliers();
  result.num_map_points = static_cast<int>(map_.num_points());
  result.num_keyframes = static_cast<int>(map_.num_keyframes());
  if (result.is_keyframe && reference_keyframe_ >= 0)  // bundle adjustment refined this frame
    frame.T_c_w = map_.keyframe(reference_keyframe_).T_c_w;
  last_frame_ = std::move(frame);
  has_last_ = true;
  return result;
}

std::vector<std::pair<TrajectoryEntry, Mat4>> System::trajectory() const {
  std::vector<std::pair<TrajectoryEntry, Mat4>> out;
  out.reserve(trajectory_.size());
  for (const auto& e : trajectory_) {
    Mat4 T_c_w = e.T_c_r;
    if (e.reference_keyframe >= 0 && map_.has_keyframe(e.reference_keyframe))
      T_c_w = e.T_c_r * map_.keyframe(e.reference_keyframe).T_c_w;
    out.emplace_back(e, geometry::se3_inverse(T_c_w));
  }
  return out;
}

}  // namespace twistslam::tracking
