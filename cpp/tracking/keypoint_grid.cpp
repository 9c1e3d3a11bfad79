#include "tracking/keypoint_grid.hpp"

#include <algorithm>
#include <cmath>

#include "tracking/frame.hpp"

namespace twistslam::tracking {

void KeypointGrid::build(const std::vector<Vec2>& uv, int width, int height, int cell_px) {
  cell_ = cell_px;
  cols_ = std::max(1, (width + cell_ - 1) / cell_);
  rows_ = std::max(1, (height + cell_ - 1) / cell_);
  cells_.assign(static_cast<size_t>(cols_) * rows_, {});
  uv_ = &uv;
  for (size_t i = 0; i < uv.size(); ++i) {
    const int c = std::clamp(static_cast<int>(uv[i].x()) / cell_, 0, cols_ - 1);
    const int r = std::clamp(static_cast<int>(uv[i].y()) / cell_, 0, rows_ - 1);
    cells_[r * cols_ + c].push_back(static_cast<int>(i));
  }
}

void KeypointGrid::query(double u, double v, double radius, std::vector<int>* out) const {
  out->clear();
  if (!uv_ || !std::isfinite(u) || !std::isfinite(v)) return;
  const int c0 = std::max(0, static_cast<int>(std::floor((u - radius) / cell_)));
  const int c1 = std::min(cols_ - 1, static_cast<int>(std::floor((u + radius) / cell_)));
  const int r0 = std::max(0, static_cast<int>(std::floor((v - radius) / cell_)));
  const int r1 = std::min(rows_ - 1, static_cast<int>(std::floor((v + radius) / cell_)));
  const double r2 = radius * radius;
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c)
      for (int i : cells_[r * cols_ + c])
        if (((*uv_)[i] - Vec2(u, v)).squaredNorm() <= r2) out->push_back(i);
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
