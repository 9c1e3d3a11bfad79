#pragma once
// Synthetic KITTI-like scenes for the optim tests: a street along +z of the first camera,
// points 3-60 m in front, the KITTI sequence 0001 stereo rig, 1 px keypoint noise scaled by
// an ORB-like octave (sigma = 1.2^level).
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "common/kitti_camera.hpp"
#include "geometry/se3.hpp"
#include "geometry/stereo_camera.hpp"
#include "optim/optim.hpp"

namespace twistslam::optim::testing {

using test_scenes::kitti_camera;

inline double rotation_error_deg(const Mat4& A, const Mat4& B) {
  const Mat3 dR = A.topLeftCorner<3, 3>().transpose() * B.topLeftCorner<3, 3>();
  return std::acos(std::clamp((dR.trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / M_PI;
}

// Distance between the camera centres of two T_c_w.
inline double translation_error(const Mat4& A, const Mat4& B) {
  return (geometry::se3_inverse(A).topRightCorner<3, 1>() -
          geometry::se3_inverse(B).topRightCorner<3, 1>())
      .norm();
}

// exp([t_dir * t; r_dir * angle]) applied on the left of T, with random unit directions.
inline Mat4 perturb(const Mat4& T, double t, double angle_rad, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  const Vec3 a = Vec3(n(rng), n(rng), n(rng)).normalized();
  const Vec3 b = Vec3(n(rng), n(rng), n(rng)).normalized();
  Vec6 xi;
  xi << a * t, b * angle_rad;
  // exp(xi) T moves the camera centre by about R^T (a t): the camera frame rotation mixes in.
  return geometry::se3_exp(xi) * T;
}

// Camera of keyframe k of a street drive: 1.5 m forward per keyframe, a slow left turn.
inline Mat4 street_pose(int k) {
  const double yaw = 0.01 * k;  // rad, about the camera's y (down) axis
  Mat3 R_w_c;
  R_w_c << std::cos(yaw), 0, std::sin(yaw), 0, 1, 0, -std::sin(yaw), 0, std::cos(yaw);
  const Vec3 centre(0.3 * std::sin(0.2 * k), 0.02 * k, 1.5 * k);
  return geometry::se3_inverse(geometry::make_pose(R_w_c, centre));
}

// A point of the street scene: facades at |x| 6-14 m, road and cars below, some far.
inline Vec3 street_point(std::mt19937& rng, double z_min, double z_max) {
  std::uniform_real_distribution<double> u(0, 1);
  const double z = z_min + (z_max - z_min) * u(rng);
  const double side = u(rng) < 0.5 ? -1 : 1;
  const double x = u(rng) < 0.7 ? side * (6 + 8 * u(rng)) : -6 + 12 * u(rng);
  const double y = -4 + 5.6 * u(rng);  // y down: 1.6 m is the road under the camera
  return Vec3(x, y, z);
}

struct Keypoint {
  Vec2 uv;
  double u_right;
  double inv_sigma2;
};

// Noisy keypoint of X_c (frame c) if visible (3-60 m, inside the image), octave-scaled noise.
inline bool observe(const geometry::StereoCamera& cam, const Vec3& X_c, bool stereo,
                    std::mt19937& rng, Keypoint* kp, double noise_px = 1.0) {
  const Vec3 Xl = X_c + cam.t_left;
  if (Xl.z() < 3 || Xl.z() > 60) return false;
  const Vec2 uv = cam.project(X_c);
  if (!cam.in_image(uv, 5)) return false;
  std::uniform_int_distribution<int> level(0, 3);
  std::normal_distribution<double> n(0, 1);
  const double sigma = std::pow(1.2, level(rng));
  kp->inv_sigma2 = 1.0 / (sigma * sigma);
  kp->uv = uv + noise_px * sigma * Vec2(n(rng), n(rng));
  kp->u_right = stereo ? cam.project_right(X_c).x() + noise_px * sigma * n(rng) : -1.0;
  return true;
}

// A wrong correspondence: a random pixel (and a random disparity for stereo).
inline Keypoint gross_outlier(const geometry::StereoCamera& cam, bool stereo, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  Keypoint kp;
  kp.uv = Vec2(5 + (cam.width - 10) * u(rng), 5 + (cam.height - 10) * u(rng));
  kp.u_right = stereo ? kp.uv.x() - (1 + 80 * u(rng)) : -1.0;
  kp.inv_sigma2 = 1.0;
  return kp;
}

}  // namespace twistslam::optim::testing
