#pragma once
// Test scenes for the features module: random multi-scale textures, and textured planes
// rendered exactly (per-pixel ray casting, bilinear texture sampling) for the left and right
// cameras of KITTI tracking sequence 0000, with ground-truth plane ids.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "geometry/stereo_camera.hpp"

namespace twistslam::features::test {

// P2 / P3 of KITTI tracking sequence 0000 (training/calib/0000.txt); images are 1242 x 375.
inline geometry::StereoCamera kitti_camera() {
  Mat34 P2, P3;
  P2 << 721.5377, 0, 609.5593, 44.85728, 0, 721.5377, 172.854, 0.2163791, 0, 0, 1, 0.002745884;
  P3 << 721.5377, 0, 609.5593, -339.5242, 0, 721.5377, 172.854, 2.199936, 0, 0, 1, 0.002729905;
  return geometry::StereoCamera::from_kitti(P2, P3, 1242, 375);
}

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
  Vec3 X_c = Vec3::Zero();
};

// Nearest plane along the ray of pixel (u, v) of the camera whose centre is -offset in frame c.
inline Hit cast_ray(const std::vector<Plane>& planes, const geometry::StereoCamera& cam,
                    const Vec3& offset, double u, double v) {
  Hit hit;
  double best = std::numeric_limits<double>::infinity();
  const Vec3 o = -offset;
  const Vec3 d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
  for (int k = 0; k < static_cast<int>(planes.size()); ++k) {
    const Plane& p = planes[k];
    const double s = p.z - o.z();
    if (s <= 0 || s >= best) continue;
    const Vec3 X = o + s * d;
    if (X.x() < p.x0 || X.x() > p.x1 || X.y() < p.y0 || X.y() > p.y1) continue;
    best = s;
    hit = {k, X};
  }
  return hit;
}

// Renders the planes for the left (right = false) or right camera; ids gets the plane index
// of every pixel (-1 = none, rendered black). noise_sigma: grey levels of Gaussian noise.
inline cv::Mat render(const std::vector<Plane>& planes, const geometry::StereoCamera& cam,
                      bool right, cv::Mat* ids, double noise_sigma, std::uint64_t seed) {
  const Vec3 offset = right ? cam.t_right : cam.t_left;
  cv::Mat img(cam.height, cam.width, CV_32F, cv::Scalar(0));
  if (ids) ids->create(cam.height, cam.width, CV_32S);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Hit h = cast_ray(planes, cam, offset, u, v);
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

// True if every pixel of the box of half side r around (u, v) has plane id `plane`.
inline bool box_on_plane(const cv::Mat& ids, double u, double v, double r, int plane) {
  const int x0 = static_cast<int>(std::floor(u - r)), x1 = static_cast<int>(std::ceil(u + r));
  const int y0 = static_cast<int>(std::floor(v - r)), y1 = static_cast<int>(std::ceil(v + r));
  if (x0 < 0 || y0 < 0 || x1 >= ids.cols || y1 >= ids.rows) return false;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      if (ids.at<int>(y, x) != plane) return false;
  return true;
}

// Three planes at 7, 15 and 40 m (the far one fills the background).
inline std::vector<Plane> three_planes(const geometry::StereoCamera& cam) {
  return {make_plane(40.0, -40, -12, 40, 12, 1.3, cam.fx, 11),
          make_plane(15.0, -1.0, -3.0, 6.0, 1.5, 1.3, cam.fx, 12),
          make_plane(7.0, -5.0, -2.0, -0.5, 1.2, 1.3, cam.fx, 13)};
}

// A textured road: the plane Y = height of frame c (y points down), x in [x0, x0 + extent],
// z in [z0, z0 + extent]. Strongly slanted in depth: its disparity changes by
// fx b / (fy height) ~ 0.32 px per image row on KITTI.
struct Ground {
  double height = 1.65, x0 = -30.0, z0 = 3.0, extent = 59.0;
  double texel = 0.04;  // m
  cv::Mat texture;      // CV_32F, (extent / texel + 3)^2
};

inline Ground make_ground(std::uint64_t seed) {
  Ground g;
  const int n = static_cast<int>(std::ceil(g.extent / g.texel)) + 3;
  g.texture = random_texture(n, n, seed);
  return g;
}

// Point of the road seen at pixel (u, v) by the camera whose centre is -offset in frame c.
inline bool cast_ground(const Ground& g, const geometry::StereoCamera& cam, const Vec3& offset,
                        double u, double v, Vec3* X) {
  const Vec3 o = -offset;
  const Vec3 d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
  if (d.y() <= 1e-9) return false;
  const Vec3 P = o + (g.height - o.y()) / d.y() * d;
  if (P.x() < g.x0 || P.x() > g.x0 + g.extent || P.z() < g.z0 || P.z() > g.z0 + g.extent)
    return false;
  *X = P;
  return true;
}

// The road (sky = flat grey), each pixel the mean of ss x ss samples: the texture is seen at
// grazing angles, where a single bilinear sample per pixel would alias differently in each view.
inline cv::Mat render_ground(const Ground& g, const geometry::StereoCamera& cam, bool right,
                             int ss, double noise_sigma, std::uint64_t seed) {
  const Vec3 offset = right ? cam.t_right : cam.t_left;
  cv::Mat img(cam.height, cam.width, CV_32F);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      double acc = 0;
      for (int a = 0; a < ss; ++a) {
        for (int b = 0; b < ss; ++b) {
          Vec3 X;
          const double du = (a + 0.5) / ss - 0.5, dv = (b + 0.5) / ss - 0.5;
          acc += cast_ground(g, cam, offset, u + du, v + dv, &X)
                     ? bilinear(g.texture, 1.0 + (X.z() - g.z0) / g.texel,
                                1.0 + (X.x() - g.x0) / g.texel)
                     : 128.0;
        }
      }
      img.at<float>(v, u) = static_cast<float>(acc / (ss * ss));
    }
  }
  cv::Mat noise(img.size(), CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
  img += noise;
  return to_u8(img);
}

}  // namespace twistslam::features::test
