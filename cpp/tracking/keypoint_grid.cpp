#include "tracking/keypoint_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "tracking/frame.hpp"

namespace twistslam::tracking {

namespace {
// Cell index of coordinate x (px) on a grid of `count` cells of `cell` px, clamped to the
// grid. Clamped while still a double: converting a value beyond int's range (a point
// projected from near the camera plane, an infinite search radius) is undefined behaviour.
int cell_index(double x, int cell, int count) {
  const double index = std::floor(x / cell);
  return static_cast<int>(std::clamp(index, 0.0, static_cast<double>(count - 1)));
}
}  // namespace

void KeypointGrid::build(const std::vector<Vec2>& uv, int width, int height, int cell_px) {
  if (cell_px < 1) throw std::invalid_argument("KeypointGrid::build: cell_px must be >= 1");
  cell_ = cell_px;
  cols_ = std::max(1, (width + cell_ - 1) / cell_);
  rows_ = std::max(1, (height + cell_ - 1) / cell_);
  cells_.assign(static_cast<size_t>(cols_) * rows_, {});
  uv_ = uv;
  built_ = true;
  for (size_t i = 0; i < uv.size(); ++i) {
    if (!uv[i].allFinite()) continue;  // never found by a query
    const int c = cell_index(uv[i].x(), cell_, cols_);
    const int r = cell_index(uv[i].y(), cell_, rows_);
    cells_[r * cols_ + c].push_back(static_cast<int>(i));
  }
}

void KeypointGrid::query(double u, double v, double radius, std::vector<int>* out) const {
  out->clear();
  if (!built_ || !std::isfinite(u) || !std::isfinite(v) || !(radius >= 0)) return;
  const int c0 = cell_index(u - radius, cell_, cols_), c1 = cell_index(u + radius, cell_, cols_);
  const int r0 = cell_index(v - radius, cell_, rows_), r1 = cell_index(v + radius, cell_, rows_);
  const double r2 = radius * radius;
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c)
      for (int i : cells_[r * cols_ + c])
        if ((uv_[i] - Vec2(u, v)).squaredNorm() <= r2) out->push_back(i);
}

int Frame::num_matched_inliers() const {
  int n = 0;
  for (size_t i = 0; i < point_ids.size(); ++i) n += point_ids[i] >= 0 && !outlier[i];
  return n;
}

void Frame::clear_matches() {
  point_ids.assign(keypoints.size(), -1);
  outlier.assign(keypoints.size(), 0);
}

}  // namespace twistslam::tracking
