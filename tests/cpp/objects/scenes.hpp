#pragma once
// Scripted scenes for the object tracker tests: boxes in the KITTI camera frame
// (x right, y down, z forward, yaw about y), car trajectories under constant twist, and the
// detections they produce.
#include <cmath>
#include <random>
#include <vector>

#include "geometry/box3d.hpp"
#include "geometry/se3.hpp"
#include "objects/tracker.hpp"

namespace scenes {

using twistslam::Mat3;
using twistslam::Mat4;
using twistslam::Vec3;
using twistslam::geometry::Box3D;
using twistslam::objects::Detection;

inline const Mat4 kI = Mat4::Identity();  // camera pose when tracking in the camera frame

inline Vec3 position(const Mat4& T) { return T.block<3, 1>(0, 3); }

inline Box3D make_box(double x, double y, double z, double l, double w, double h, double yaw) {
  Box3D b;
  b.center = Vec3(x, y, z);
  b.length = l, b.width = w, b.height = h, b.yaw = yaw;
  return b;
}

// Same convention as Box3D::pose(): the box's x axis is (cos yaw, 0, -sin yaw).
inline Mat3 rot_y(double a) {
  Mat3 R;
  R << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return R;
}

inline Mat4 pose_yaw(double yaw, const Vec3& t) {
  return twistslam::geometry::make_pose(rot_y(yaw), t);
}

// Yaw of an upright pose (rotation about y).
inline double yaw_of(const Mat4& T) { return std::atan2(T(0, 2), T(0, 0)); }

inline double wrap_angle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

inline const Vec3 kCarSize(4.0, 1.6, 1.5);  // l, w, h

// A car driving forward (along its own x axis) at v m/frame while turning at omega rad/frame:
// a constant world twist, the motion model's exact case. Ground at y = 1.65 (camera height),
// so the geometric centre is at y = 1.65 - h/2.
struct Car {
  Vec3 p0 = Vec3(0, 0.9, 20);
  double yaw0 = 0;
  double v = 1.0;
  double omega = 0;

  Mat4 pose(double t) const {
    const double yaw = yaw0 + omega * t;
    Vec3 p;
    if (std::abs(omega) < 1e-12) {
      p = p0 + v * t * Vec3(std::cos(yaw0), 0, -std::sin(yaw0));
    } else {
      p = p0 + (v / omega) * Vec3(std::sin(yaw) - std::sin(yaw0), 0, std::cos(yaw) - std::cos(yaw0));
    }
    return pose_yaw(yaw, p);
  }
};

// The options every scene is written for, set explicitly so that tuning the library's
// defaults (python/twistslam/config_objects.py) does not change what the tests mean. The
// window's own options (size, sigmas, iterations) stay the library's defaults.
inline twistslam::objects::TrackerOptions options() {
  twistslam::objects::TrackerOptions o;
  o.metric = twistslam::objects::AssociationMetric::kGiou3d;
  o.max_cost = 1.2;
  o.second_pass = true;
  o.second_pass_max_cost = 1.0;
  o.high_score = 0.5;  // the scenes' detections score 0.9
  o.low_score = 0.0;
  o.birth_score = 0.5;
  o.birth_hits = 3;
  o.max_misses = 2;
  o.tentative_max_misses = 0;
  o.ground_normal = Vec3(0, -1, 0);
  o.optimize = true;
  o.report_tentative_frames = true;
  o.max_reported_gap = 3;
  o.interpolate_gaps = true;
  o.miss_turn_decay = 1.0;  // constant velocity through misses (the motion model's exact case)
  o.range_score_slope = 0;  // raw scores: the scenes' cars are near anyway
  o.range_score_start = 35;
  o.backcast_frames = 0;    // no backcast unless a test asks for it
  o.backcast_min_range = 45;
  return o;
}

// The detection of a box at pose T_c_o (upright in the camera frame).
inline Detection detect(const Mat4& T_c_o, double score = 0.9, int class_id = 0,
                        const Vec3& size = kCarSize) {
  Detection d;
  d.box = make_box(T_c_o(0, 3), T_c_o(1, 3), T_c_o(2, 3), size[0], size[1], size[2], yaw_of(T_c_o));
  d.score = score;
  d.class_id = class_id;
  return d;
}

// The same with Gaussian noise on the centre (sigma_t, each axis) and the yaw (sigma_yaw).
inline Detection detect_noisy(const Mat4& T_c_o, double sigma_t, double sigma_yaw, std::mt19937& rng,
                              double score = 0.9) {
  std::normal_distribution<double> n(0.0, 1.0);
  Detection d = detect(T_c_o, score);
  d.box.center += sigma_t * Vec3(n(rng), n(rng), n(rng));
  d.box.yaw += sigma_yaw * n(rng);
  return d;
}

// The track holding detection `index` of `frame`, or -1 (its position in `tracks`).
inline int track_with_detection(const std::vector<twistslam::objects::ObjectTrack>& tracks, int frame,
                                int index) {
  for (size_t k = 0; k < tracks.size(); ++k) {
    const auto* f = tracks[k].at(frame);
    if (f && f->detected && f->detection_index == index) return static_cast<int>(k);
  }
  return -1;
}

inline int count_reported(const twistslam::objects::ObjectTrack& t) {
  int n = 0;
  for (const auto& f : t.frames) n += f.reported;
  return n;
}

}  // namespace scenes
