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

bool flow_at(const cv::Mat& flow, const Vec2& uv, Vec2* out) {
  if (flow.empty()) return false;
  const double x = uv.x(), y = uv.y();
  if (!(x >= 0 && y >= 0 && x <= flow.cols - 1 && y <= flow.rows - 1)) return false;
  const int x0 = std::min(static_cast<int>(x), flow.cols - 2 < 0 ? 0 : flow.cols - 2);
  const int y0 = std::min(static_cast<int>(y), flow.rows - 2 < 0 ? 0 : flow.rows - 2);
  const int x1 = std::min(x0 + 1, flow.cols - 1), y1 = std::min(y0 + 1, flow.rows - 1);
  const double ax = x - x0, ay = y - y0;
  Vec2 f = Vec2::Zero();
  const cv::Vec2f f00 = flow.at<cv::Vec2f>(y0, x0), f01 = flow.at<cv::Vec2f>(y0, x1),
                  f10 = flow.at<cv::Vec2f>(y1, x0), f11 = flow.at<cv::Vec2f>(y1, x1);
  for (int k = 0; k < 2; ++k)
    f[k] = (1 - ay) * ((1 - ax) * f00[k] + ax * f01[k]) + ay * ((1 - ax) * f10[k] + ax * f11[k]);
  if (!f.allFinite()) return false;
  *out = uv + f;
  return true;
}

}  // namespace twistslam::tracking
