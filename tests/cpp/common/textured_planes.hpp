#pragma once
// Textured fronto-parallel planes rendered exactly (per-pixel ray casting, bilinear texture
// sampling) for the left and right cameras of a rectified rig, with ground-truth plane ids:
// the features tests render them in frame c, the tracking tests in a world frame for a moving
// rig.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "common/kitti_camera.hpp"
#include "geometry/stereo_camera.hpp"

namespace twistslam::test_scenes {

// Float texture (mean ~128, std ~40): blurred noise at three scales plus random discs and
// rectangles, so that FAST finds corners at every pyramid level.
inline cv::Mat random_texture(int width, int height, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat acc = cv::Mat::zeros(height, width, CV_32F);
  const double sigmas[] = {0.8, 2.0, 5.0};
  const double weights[] = {0.6, 0.8, 1.0};
  for (int k = 0; k < 3; ++k) {
    cv::Mat noise(height, width, CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
    cv::GaussianBlur(noise, noise, cv::Size(), sigmas[k]);
    cv::Scalar mean, stddev;
    cv::meanStdDev(noise, mean, stddev);
    acc += noise * (weights[k] / stddev[0]);
  }
  cv::Mat shapes = cv::Mat::zeros(height, width, CV_32F);
  const int count = width * height / 400;
  for (int i = 0; i < count; ++i) {
    const cv::Point c(rng.uniform(0, width), rng.uniform(0, height));
    const double value = rng.uniform(-1.5, 1.5);
    const int r = rng.uniform(2, 9);
    if (i % 2)
      cv::circle(shapes, c, r, cv::Scalar(value), cv::FILLED, cv::LINE_8);
    else
      cv::rectangle(shapes, cv::Rect(c.x, c.y, r * 2, rng.uniform(2, 2 * r + 1)),
                    cv::Scalar(value), cv::FILLED);
  }
  cv::GaussianBlur(shapes, shapes, cv::Size(), 0.7);
  acc += shapes;
  cv::Scalar mean, stddev;
  cv::meanStdDev(acc, mean, stddev);
  acc = (acc - mean[0]) * (40.0 / stddev[0]) + 128.0;
  return acc;
}

inline cv::Mat to_u8(const cv::Mat& f) {
  cv::Mat out;
  f.convertTo(out, CV_8U);  // rounds and saturates
  return out;
}

// A fronto-parallel textured rectangle at depth z of frame c.
struct Plane {
  double z;                 // m, in frame c
  double x0, y0, x1, y1;    // extent in frame c (m)
  double texel;             // m per texture pixel
  cv::Mat texture;          // CV_32F
};

inline Plane make_plane(double z, double x0, double y0, double x1, double y1, double px_per_texel,
                        double fx, std::uint64_t seed) {
  Plane p{z, x0, y0, x1, y1, px_per_texel * z / fx, {}};
  const int w = static_cast<int>(std::ceil((x1 - x0) / p.texel)) + 3;
  const int h = static_cast<int>(std::ceil((y1 - y0) / p.texel)) + 3;
  p.texture = random_texture(w, h, seed);
  return p;
}

inline float bilinear(const cv::Mat& t, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float ax = static_cast<float>(x - x0), ay = static_cast<float>(y - y0);
  const float* r0 = t.ptr<float>(y0);
  const float* r1 = t.ptr<float>(y0 + 1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) +
         ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
}

struct Hit {
  int plane = -1;
  Vec3 X_c = Vec3::Zero();  // the point, in the planes' frame
};

// Nearest plane along the ray o + s d (s > 0), all in the planes' frame.
inline Hit cast(const std::vector<Plane>& planes, const Vec3& o, const Vec3& d) {
  Hit hit;
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < static_cast<int>(planes.size()); ++k) {
    const Plane& p = planes[k];
    if (std::abs(d.z()) < 1e-12) continue;
    const double s = (p.z - o.z()) / d.z();
    if (s <= 0 || s >= best) continue;
    const Vec3 X = o + s * d;
    if (X.x() < p.x0 || X.x() > p.x1 || X.y() < p.y0 || X.y() > p.y1) continue;
    best = s;
    hit = {k, X};
  }
  return hit;
}

// Nearest plane along the ray of pixel (u, v) of the camera whose centre is -offset in frame
// c, the planes given in frame c (hit.X_c).
inline Hit cast_ray(const std::vector<Plane>& planes, const geometry::StereoCamera& cam,
                    const Vec3& offset, double u, double v) {
  return cast(planes, -offset, Vec3((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0));
}

// Renders the planes (given in a world frame w) for the left (right = false) or right camera
// of the rig at pose T_w_c; ids gets the plane index of every pixel (-1 = none, rendered
// black). noise_sigma: grey levels of Gaussian noise.
inline cv::Mat render(const std::vector<Plane>& planes, const geometry::StereoCamera& cam,
                      const Mat4& T_w_c, bool right, cv::Mat* ids, double noise_sigma,
                      std::uint64_t seed) {
  const Vec3 offset = right ? cam.t_right : cam.t_left;
  const Mat3 R = T_w_c.topLeftCorner<3, 3>();
  const Vec3 origin = R * (-offset) + T_w_c.topRightCorner<3, 1>();
  cv::Mat img(cam.height, cam.width, CV_32F, cv::Scalar(0));
  if (ids) ids->create(cam.height, cam.width, CV_32S);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Hit h = cast(planes, origin, R * Vec3((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0));
      if (ids) ids->at<int>(v, u) = h.plane;
      if (h.plane < 0) continue;
      const Plane& p = planes[h.plane];
      img.at<float>(v, u) = bilinear(p.texture, 1.0 + (h.X_c.x() - p.x0) / p.texel,
                                     1.0 + (h.X_c.y() - p.y0) / p.texel);
    }
  }
  if (noise_sigma > 0) {
    cv::Mat noise(img.size(), CV_32F);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
    img += noise;
  }
  return to_u8(img);
}

// The same with the planes given in frame c (the rig at the origin).
inline cv::Mat render(const std::vector<Plane>& planes, const geometry::StereoCamera& cam,
                      bool right, cv::Mat* ids, double noise_sigma, std::uint64_t seed) {
  return render(planes, cam, Mat4::Identity(), right, ids, noise_sigma, seed);
}

}  // namespace twistslam::test_scenes
