#pragma once
// Synthetic scenes of the visual object tracking tests: keypoints that are exact projections
// of rigid car-like clusters moving on the road plane in front of a static camera, with
// per-frame panoptic instance ids that change every frame, a static background, the optical
// flow at the cars' keypoints. Shared by test_object_tracker.cpp and
// test_object_detection_fusion.cpp (an anonymous namespace: each test file its own copy).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "common/kitti_camera.hpp"
#include "common/random_descriptor.hpp"
#include "geometry/se3.hpp"
#include "geometry/so3.hpp"
#include "tracking/object_tracker.hpp"

namespace {
using namespace twistslam;

const geometry::StereoCamera kCamera = test_scenes::kitti_camera();
const Vec3 kUp(0, -1, 0);
constexpr int kCar = 26, kRoad = 7;

using test_scenes::random_descriptor;

// A rigid object: points in its own frame, a descriptor each, pose P_i = (R(yaw_i), c_i) in
// the world with planar motion about kUp. It drives like a vehicle: its velocity turns with
// its yaw (constant in its own frame), as the tracker's non-holonomic heading prior expects.
struct Car {
  std::vector<Vec3> X_o;
  std::vector<map::Descriptor> descriptors;
  Vec3 c0 = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();  // m/frame, world at frame 0 (turns with the yaw)
  double yaw_rate = 0;           // rad/frame about kUp
  double yaw0 = 0;               // rad about kUp at frame 0 (pi / 2: x along the camera's z)
  int label = kCar;

  Mat4 pose(int i) const {
    Vec3 c = c0;
    for (int k = 0; k < i; ++k) c += geometry::so3_exp(kUp * (yaw_rate * k)) * velocity;
    return geometry::make_pose(geometry::so3_exp(kUp * (yaw0 + yaw_rate * i)), c);
  }
  // True world-frame motion from frame i to i + 1: P_{i+1} P_i^-1.
  Mat4 motion(int i) const { return pose(i + 1) * geometry::se3_inverse(pose(i)); }
};

Car make_car(std::mt19937& rng, const Vec3& c0, const Vec3& velocity, double yaw_rate,
             int n = 80) {
  Car car;
  car.c0 = c0;
  car.velocity = velocity;
  car.yaw_rate = yaw_rate;
  std::uniform_real_distribution<double> x(-2.0, 2.0), y(-0.75, 0.75), z(-0.9, 0.9);
  for (int k = 0; k < n; ++k) {
    car.X_o.emplace_back(x(rng), y(rng), z(rng));
    car.descriptors.push_back(random_descriptor(rng));
  }
  return car;
}

struct Background {
  std::vector<Vec3> X_w;
  std::vector<map::Descriptor> descriptors;
};

Background make_background(std::mt19937& rng, int n = 50) {
  Background b;
  std::uniform_real_distribution<double> u(5, kCamera.width - 6.0), v(5, kCamera.height - 6.0),
      depth(30, 50);
  for (int k = 0; k < n; ++k) {
    b.X_w.push_back(kCamera.backproject(Vec2(u(rng), v(rng)), depth(rng)));
    b.descriptors.push_back(random_descriptor(rng));
  }
  return b;
}

// A frame under construction, camera at the world origin (T_c_w = I).
struct SceneFrame {
  tracking::Frame frame;
  cv::Mat instances;  // CV_32SC1, 0 = none
  cv::Mat flow;       // CV_32FC2, NaN where unknown (filled at the car's keypoints)
  bool mono = false;  // keypoints without a stereo match (the right camera does not see them)
  bool round_uv = false;  // keypoint positions rounded to whole pixels (mask pixels as keypoints)
  double stereo_depth_scale = 1.0;  // stereo depth of every keypoint times this (a disparity bias)
  // > 0 with noise_rng: Gaussian noise of every stereo match's right column (px), the depth
  // following the disparity (a real matcher's sub-pixel error)
  double disparity_noise_px = 0;
  std::mt19937* noise_rng = nullptr;

  explicit SceneFrame(int index) {
    frame.index = index;
    frame.timestamp = 0.1 * index;
    instances = cv::Mat::zeros(kCamera.height, kCamera.width, CV_32SC1);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    flow = cv::Mat(kCamera.height, kCamera.width, CV_32FC2, cv::Scalar(nan, nan));
  }

  // Adds the stereo keypoint of X_c; false when it falls outside the image.
  bool add_point(const Vec3& X_c, const map::Descriptor& d, int label, int octave) {
    Vec2 uv = kCamera.project(X_c);
    if (X_c.z() <= 0.5 || !kCamera.in_image(uv, 1.0)) return false;
    if (round_uv) uv = uv.array().round().matrix();
    auto& k = frame.keypoints;
    k.uv.push_back(uv);
    k.octave.push_back(octave);
    const Vec3 X_stereo = stereo_depth_scale * X_c;  // on the same ray, farther or nearer
    double u_right = kCamera.project_right(X_stereo).x(), depth = X_stereo.z() + kCamera.t_left.z();
    if (!mono && disparity_noise_px > 0 && noise_rng) {
      u_right += std::normal_distribution<double>(0.0, disparity_noise_px)(*noise_rng);
      depth = kCamera.depth_from_disparity(uv.x() - u_right);
    }
    k.u_right.push_back(mono ? -1.0 : u_right);
    k.depth.push_back(mono ? -1.0 : depth);
    k.descriptors.push_back(d);
    k.label.push_back(label);
    frame.usable.push_back(label == kRoad);
    return true;
  }

  void add_background(const Background& b) {
    for (size_t k = 0; k < b.X_w.size(); ++k) add_point(b.X_w[k], b.descriptors[k], kRoad, 0);
  }

  // The car's keypoints in frame i; its bounding rectangle filled with `instance` (0: no mask);
  // the flow from frame i - 1 at its keypoints of frame i - 1.
  void add_car(const Car& car, int i, int instance) {
    const Mat4 P = car.pose(i), P_prev = car.pose(i - 1);
    double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
    for (size_t k = 0; k < car.X_o.size(); ++k) {
      const Vec3 X = P.topLeftCorner<3, 3>() * car.X_o[k] + P.topRightCorner<3, 1>();
      if (!add_point(X, car.descriptors[k], car.label, static_cast<int>(k % 3))) continue;
      const Vec2 uv = frame.keypoints.uv.back();
      u0 = std::min(u0, uv.x()), v0 = std::min(v0, uv.y());
      u1 = std::max(u1, uv.x()), v1 = std::max(v1, uv.y());
      const Vec3 X_prev = P_prev.topLeftCorner<3, 3>() * car.X_o[k] + P_prev.topRightCorner<3, 1>();
      const Vec2 uv_prev = kCamera.project(X_prev);
      const Vec2 f = uv - uv_prev;
      // the 2 x 2 pixels around the previous position carry this point's flow (bilinear reads)
      for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx) {
          const int x = static_cast<int>(std::floor(uv_prev.x())) + dx;
          const int y = static_cast<int>(std::floor(uv_prev.y())) + dy;
          if (x >= 0 && y >= 0 && x < flow.cols && y < flow.rows)
            flow.at<cv::Vec2f>(y, x) = cv::Vec2f(static_cast<float>(f.x()), static_cast<float>(f.y()));
        }
    }
    if (instance > 0 && u1 >= u0) {
      const cv::Rect box(cv::Point(static_cast<int>(std::floor(u0)) - 2, static_cast<int>(std::floor(v0)) - 2),
                         cv::Point(static_cast<int>(std::ceil(u1)) + 3, static_cast<int>(std::ceil(v1)) + 3));
      instances(box & cv::Rect(0, 0, instances.cols, instances.rows)).setTo(instance);
    }
  }

  tracking::Frame& finish() {
    const size_t n = frame.keypoints.size();
    frame.point_ids.assign(n, -1);
    frame.outlier.assign(n, 0);
    frame.grid.build(frame.keypoints.uv, kCamera.width, kCamera.height);
    return frame;
  }
};

tracking::ObjectTracker make_tracker(const tracking::ObjectTrackingOptions& options = {},
                                     const tracking::ObjectLidarOptions& lidar = {}) {
  return tracking::ObjectTracker(kCamera, options, {1.0f, 1.2f, 1.44f, 1.728f},
                                 tracking::LevelWeights({1.0f, 1.44f, 2.07f, 2.99f}), lidar);
}

// Per-frame instance ids that change every frame (never the previous frame's id).
int instance_id(int i, int offset = 0) {
  static const int ids[] = {3, 7, 2, 9, 4, 11, 5, 8, 6, 12, 13, 10, 14, 15, 16, 17, 18, 19};
  return ids[(i + offset) % 18];
}

double rotation_angle_deg(const Mat3& R) {
  const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

// Each consecutive pair of track frames moves like the car (T_{i+1} T_i^-1 vs P_{i+1} P_i^-1).
void expect_motion(const objects::ObjectTrack& track, const Car& car, int first_frame) {
  for (size_t r = 0; r + 1 < track.frames.size(); ++r) {
    const int i = track.frames[r].frame;
    ASSERT_EQ(track.frames[r + 1].frame, i + 1);
    const Mat4 est = track.frames[r + 1].T_w_o * geometry::se3_inverse(track.frames[r].T_w_o);
    const Mat4 truth = car.motion(i - first_frame);
    const Mat4 err = geometry::se3_inverse(truth) * est;
    EXPECT_LT((est.topRightCorner<3, 1>() - truth.topRightCorner<3, 1>()).norm(), 0.02)
        << "frame " << i << " -> " << i + 1;
    EXPECT_LT(rotation_angle_deg(err.topLeftCorner<3, 3>()), 0.1) << "frame " << i << " -> " << i + 1;
  }
}

constexpr double kLength = 4.0, kWidth = 1.8, kHeight = 1.5;  // the car of make_car

// A LiDAR scan (frame c, camera at the origin) of the car at frame i: points drawn anew each
// frame on its sides and top (a LiDAR samples other spots every sweep), 1 cm range noise, and
// road points under and around it.
Vec3 on_car(const Car& car, int i, const Vec3& X_o) {
  const Mat4 P = car.pose(i);
  return P.topLeftCorner<3, 3>() * X_o + P.topRightCorner<3, 1>();
}

Points3 car_scan(const Car& car, int i, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Vec3> pts;
  const Vec3 half(kLength / 2, kHeight / 2, kWidth / 2);
  for (int k = 0; k < 600; ++k) {
    Vec3 q(u(rng) * half.x(), u(rng) * half.y(), u(rng) * half.z());
    const int face = k % 5;  // +-x, +-z, top (-y)
    if (face == 0) q.x() = half.x();
    if (face == 1) q.x() = -half.x();
    if (face == 2) q.z() = half.z();
    if (face == 3) q.z() = -half.z();
    if (face == 4) q.y() = -half.y();
    pts.push_back(on_car(car, i, q) + Vec3(noise(rng), noise(rng), noise(rng)));
  }
  for (int k = 0; k < 400; ++k)  // the road: y = the box's bottom
    pts.push_back(on_car(car, i, Vec3(u(rng) * 4, half.y(), u(rng) * 3)));
  Points3 out(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t k = 0; k < pts.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = pts[k].transpose();
  return out;
}

struct TrackerScene : ::testing::Test {
  std::mt19937 rng{1234};
  Background background = make_background(rng);
};

void run_car(tracking::ObjectTracker& tracker, const Car& car, const Background& background,
             int frames, bool use_flow, std::vector<tracking::ObjectTrackingReport>* reports) {
  for (int i = 0; i < frames; ++i) {
    SceneFrame f(i);
    f.add_car(car, i, instance_id(i));
    f.add_background(background);
    reports->push_back(tracker.track(f.finish(), f.instances, use_flow && i > 0 ? f.flow : cv::Mat(), kUp));
  }
}

// One car seen in two parts under one instance: the keypoints of `stereo_part` with a
// disparity, those of `mono_part` without (the right camera sees past an occluder there).
// Frames 0 .. frames - 1 with flow after the first; each frame's report, the 3D boxes given
// to every frame.
std::vector<tracking::ObjectTrackingReport> run_partly_stereo_car(
    tracking::ObjectTracker& tracker, const Car& stereo_part, const Car& mono_part,
    const Background& background, int frames, const std::vector<objects::Detection>& boxes = {}) {
  std::vector<tracking::ObjectTrackingReport> reports;
  for (int i = 0; i < frames; ++i) {
    SceneFrame f(i);
    f.add_car(stereo_part, i, instance_id(i));
    f.mono = true;
    f.add_car(mono_part, i, instance_id(i));
    f.mono = false;
    f.add_background(background);
    reports.push_back(tracker.track(f.finish(), f.instances, i > 0 ? f.flow : cv::Mat(), kUp,
                                    cv::Mat(), Vec4::Zero(), boxes));
  }
  return reports;
}

// A car whose keypoints take new descriptors every frame: no point is ever found again, so
// each frame re-seeds its cluster from the instance's stereo points (the cluster never
// tracked, each row one frame's stereo). Frames 0 .. frames - 1, no flow.
void run_reseeding_car(tracking::ObjectTracker& tracker, Car car, const Background& background,
                       int frames, std::mt19937& rng) {
  for (int i = 0; i < frames; ++i) {
    for (auto& d : car.descriptors) d = random_descriptor(rng);
    SceneFrame f(i);
    f.add_car(car, i, instance_id(i));
    f.add_background(background);
    tracker.track(f.finish(), f.instances, cv::Mat(), kUp);
  }
}

// Frames 0..frames-1 of `car` (frame 0 of `born`: a car seen elsewhere at its birth), its
// keypoints' descriptors new every frame from frame `found_frames` on (nothing found again:
// the cluster re-seeds from its instance), one instance id throughout.
void run_car_losing_descriptors(tracking::ObjectTracker& tracker, const Car& born, Car car,
                                const Background& background, int frames, int found_frames,
                                std::mt19937& rng) {
  for (int i = 0; i < frames; ++i) {
    if (i >= found_frames)
      for (auto& d : car.descriptors) d = random_descriptor(rng);
    SceneFrame f(i);
    f.add_car(i == 0 ? born : car, i, 5);
    f.add_background(background);
    tracker.track(f.finish(), f.instances, cv::Mat(), kUp);
  }
}

}  // namespace
