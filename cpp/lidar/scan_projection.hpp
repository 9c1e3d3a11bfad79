#pragma once
// A LiDAR scan projected into the left image, bucketed by pixel cell (built once per frame,
// queried per keypoint). Returns on a-priori dynamic classes (mask == 0) are dropped here, so
// no later step can use them (eq. 3 of the paper: dynamic classes are never static evidence).
#include <opencv2/core/mat.hpp>
#include <vector>

#include "geometry/stereo_camera.hpp"
#include "geometry/types.hpp"
#include "lidar/lidar_depth_options.hpp"

namespace twistslam::lidar {

struct ProjectedReturn {
  float u = 0, v = 0;  // px, left image
  float depth = 0;     // m, along the left optical axis (X_left.z)
  int index = 0;       // row of the input scan
};

struct ScanProjection {
  int width = 0, height = 0;  // px, image size
  double cell_size = 1.0;     // px
  int cols = 0, rows = 0;     // buckets
  // Returns sorted by bucket; bucket b holds returns[cell_start[b] .. cell_start[b + 1]).
  std::vector<ProjectedReturn> returns;
  std::vector<int> cell_start;
  int num_non_finite = 0;  // input points with a NaN / Inf coordinate (dropped)
  int num_masked = 0;      // returns in the image on mask == 0 pixels (dropped)

  // Calls visit(const ProjectedReturn&) for every return whose bucket meets the square
  // [u - r, u + r] x [v - r, v + r] (the caller tests the exact distance).
  template <typename Visit>
  void for_each_near(double u, double v, double r, Visit&& visit) const;
};

// Projects points_c (N x 3, rectified reference camera frame c) into the left image of
// `camera` (needs width / height). Non-finite points are dropped and counted. `mask` is empty
// or CV_8UC1 of the image size, 0 = dynamic class. Throws std::invalid_argument on a camera
// without image size, a mask of the wrong size / type, or invalid options.
ScanProjection project_scan(const Eigen::Ref<const Points3>& points_c,
                            const geometry::StereoCamera& camera,
                            const LidarDepthOptions& options, const cv::Mat& mask = cv::Mat());

template <typename Visit>
void ScanProjection::for_each_near(double u, double v, double r, Visit&& visit) const {
  if (cols == 0 || rows == 0) return;
  auto clamp_cell = [](double x, int n) {
    const int i = static_cast<int>(x);
    return i < 0 ? 0 : (i >= n ? n - 1 : i);
  };
  if (u + r < 0 || v + r < 0 || u - r >= cols * cell_size || v - r >= rows * cell_size) return;
  const int c0 = clamp_cell((u - r) / cell_size, cols), c1 = clamp_cell((u + r) / cell_size, cols);
  const int r0 = clamp_cell((v - r) / cell_size, rows), r1 = clamp_cell((v + r) / cell_size, rows);
  for (int row = r0; row <= r1; ++row)
    for (int col = c0; col <= c1; ++col) {
      const int b = row * cols + col;
      for (int i = cell_start[b]; i < cell_start[b + 1]; ++i) visit(returns[i]);
    }
}

}  // namespace twistslam::lidar
