#include "tracking/instance_pixels.hpp"

#include <algorithm>
#include <cmath>

namespace twistslam::tracking {

int pixel_value(const cv::Mat& image, const Vec2& uv) {
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  if (u < 0 || v < 0 || u >= image.cols || v >= image.rows) return 0;
  return image.at<int>(v, u);
}

int instance_at_keypoint(const cv::Mat& instances, const Vec2& uv, double radius_px) {
  const int id = pixel_value(instances, uv);
  if (id <= 0 || !(radius_px > 0)) return id;
  const int r = static_cast<int>(std::ceil(std::min(radius_px, 1000.0)));
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  for (int y = std::max(0, v - r); y <= std::min(instances.rows - 1, v + r); ++y) {
    const int* row = instances.ptr<int>(y);
    for (int x = std::max(0, u - r); x <= std::min(instances.cols - 1, u + r); ++x)
      if (row[x] > 0 && row[x] != id) return 0;
  }
  return id;
}

}  // namespace twistslam::tracking
