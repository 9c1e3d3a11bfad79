#pragma once
// Test scenes for the features module: the textured planes of common/textured_planes.hpp, and
// a textured road seen at grazing angles (supersampled), with ground truth per pixel.
#include <opencv2/core.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

#include "common/textured_planes.hpp"
#include "geometry/stereo_camera.hpp"

namespace twistslam::features::test {

using namespace twistslam::test_scenes;

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
