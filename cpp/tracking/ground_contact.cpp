#include "tracking/ground_contact.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace twistslam::tracking {

GroundContact ground_contact_depth(const cv::Mat& instances, const cv::Mat& labels,
                                   int instance, int road_class_id,
                                   const geometry::StereoCamera& camera, const Mat4& T_w_c,
                                   const Vec4& plane_w, int min_columns, double min_fraction,
                                   double max_depth_m, int max_gap_px,
                                   double depth_quantile, double contact_height_m) {
  GroundContact out;
  if (instances.empty() || labels.empty() || instances.type() != CV_32SC1 ||
      labels.type() != CV_32SC1 || instances.size() != labels.size() || instance <= 0 ||
      !plane_w.allFinite() || !(plane_w.head<3>().norm() > 0))
    return out;
  // lowest row of the instance in every column (bottom-up, so the first hit is the lowest)
  const int rows = instances.rows, cols = instances.cols;
  std::vector<int> bottom(cols, -1);
  int remaining = cols;
  for (int v = rows - 1; v >= 0 && remaining > 0; --v) {
    const int* row = instances.ptr<int>(v);
    for (int u = 0; u < cols; ++u)
      if (row[u] == instance && bottom[u] < 0) bottom[u] = v, --remaining;
  }
  // the plane in the camera frame: n_c . X_c + d_c = 0
  const Mat3 R_w_c = T_w_c.topLeftCorner<3, 3>();
  const Vec3 t_w_c = T_w_c.topRightCorner<3, 1>();
  const Vec3 n_c = R_w_c.transpose() * plane_w.head<3>();
  double d_c = plane_w.head<3>().dot(t_w_c) + plane_w(3);
  // raised towards the camera (at the origin, on the plane's d_c side)
  d_c -= std::copysign(contact_height_m * n_c.norm(), d_c);
  std::vector<double> depths;
  for (int u = 0; u < cols; ++u) {
    if (bottom[u] < 0) continue;
    bool road = false, hidden = false;
    for (int v = bottom[u] + 1; v <= std::min(rows - 1, bottom[u] + max_gap_px + 1) && !road; ++v) {
      road = labels.at<int>(v, u) == road_class_id;
      const int below = instances.at<int>(v, u);
      hidden = hidden || (below != 0 && below != instance);
    }
    if (hidden && !road) {
      ++out.hidden_columns;
      continue;
    }
    ++out.mask_columns;
    if (!road) continue;
    // the ray through the pixel's lower edge: X_c = z * ray, n_c . X_c + d_c = 0
    const Vec3 ray = camera.backproject(Vec2(u, bottom[u] + 0.5), 1.0);  // pixel centres at integers
    const double denom = n_c.dot(ray);
    if (!(std::abs(denom) > 1e-9)) continue;
    const double z = -d_c / denom;
    if (z > 0 && z <= max_depth_m && std::isfinite(z)) depths.push_back(z);
  }
  out.columns = static_cast<int>(depths.size());
  if (out.columns < std::max(1, min_columns) || out.columns < min_fraction * out.mask_columns)
    return out;
  const size_t k = std::min(depths.size() - 1,
                            static_cast<size_t>(std::clamp(depth_quantile, 0.0, 1.0) * depths.size()));
  std::nth_element(depths.begin(), depths.begin() + k, depths.end());
  out.depth = depths[k];
  out.valid = true;
  return out;
}

}  // namespace twistslam::tracking
