#include "lidar/scan_projection.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace twistslam::lidar {

namespace {

void check_inputs(const geometry::StereoCamera& camera, const cv::Mat& mask) {
  if (camera.width <= 0 || camera.height <= 0)
    throw std::invalid_argument("project_scan: the camera has no image size (width / height 0)");
  if (mask.empty()) return;
  if (mask.type() != CV_8UC1 || mask.cols != camera.width || mask.rows != camera.height)
    throw std::invalid_argument("project_scan: mask must be uint8 " +
                                std::to_string(camera.height) + " x " +
                                std::to_string(camera.width) + ", got type " +
                                std::to_string(mask.type()) + " " + std::to_string(mask.rows) +
                                " x " + std::to_string(mask.cols));
}

}  // namespace

ScanProjection project_scan(const Eigen::Ref<const Points3>& points_c,
                            const geometry::StereoCamera& camera,
                            const LidarDepthOptions& options, const cv::Mat& mask) {
  validate(options);
  check_inputs(camera, mask);
  ScanProjection out;
  out.width = camera.width;
  out.height = camera.height;
  out.cell_size = options.cell_size_px;
  out.cols = static_cast<int>(std::ceil(camera.width / options.cell_size_px));
  out.rows = static_cast<int>(std::ceil(camera.height / options.cell_size_px));

  // Pass 1: project, keep returns in the image and the depth range, remember their bucket.
  std::vector<ProjectedReturn> kept;
  std::vector<int> bucket;
  kept.reserve(points_c.rows() / 4);  // a forward camera sees about a quarter of a 360 deg scan
  bucket.reserve(points_c.rows() / 4);
  for (Eigen::Index i = 0; i < points_c.rows(); ++i) {
    const Vec3 X = points_c.row(i).transpose();
    if (!X.allFinite()) {
      ++out.num_non_finite;
      continue;
    }
    const Vec3 X_left = X + camera.t_left;  // stereo_camera.hpp: X_left = X_c + t_left
    const double z = X_left.z();
    if (z < options.min_depth_m || z > options.max_depth_m) continue;
    const double u = camera.fx * X_left.x() / z + camera.cx;
    const double v = camera.fy * X_left.y() / z + camera.cy;
    if (!(u >= 0 && v >= 0 && u < camera.width && v < camera.height)) continue;
    if (!mask.empty() && mask.at<unsigned char>(static_cast<int>(v), static_cast<int>(u)) == 0) {
      ++out.num_masked;
      continue;
    }
    kept.push_back({static_cast<float>(u), static_cast<float>(v), static_cast<float>(z),
                    static_cast<int>(i)});
    const int col = std::min(static_cast<int>(u / out.cell_size), out.cols - 1);
    const int row = std::min(static_cast<int>(v / out.cell_size), out.rows - 1);
    bucket.push_back(row * out.cols + col);
  }

  // Pass 2: counting sort by bucket (O(N), stable: returns keep the scan order in a bucket).
  out.cell_start.assign(static_cast<std::size_t>(out.cols) * out.rows + 1, 0);
  for (const int b : bucket) ++out.cell_start[b + 1];
  for (std::size_t b = 1; b < out.cell_start.size(); ++b) out.cell_start[b] += out.cell_start[b - 1];
  std::vector<int> next(out.cell_start.begin(), out.cell_start.end() - 1);
  out.returns.resize(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) out.returns[next[bucket[k]]++] = kept[k];
  return out;
}

}  // namespace twistslam::lidar
