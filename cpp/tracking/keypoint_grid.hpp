#pragma once
// Uniform grid over the image for radius queries on keypoints (projection matching).
#include <vector>

#include "geometry/types.hpp"

namespace twistslam::tracking {

class KeypointGrid {
 public:
  // Throws std::invalid_argument for cell_px < 1. Non-finite keypoints are left out.
  void build(const std::vector<Vec2>& uv, int width, int height, int cell_px = 32);
  // Indices of keypoints within `radius` px of (u, v) (square window, then exact distance);
  // none for a non-finite (u, v) or a NaN / negative radius. Any finite or infinite radius
  // and any position are safe (cells are clamped before they become ints).
  void query(double u, double v, double radius, std::vector<int>* out) const;

 private:
  int cell_ = 32, cols_ = 0, rows_ = 0;
  std::vector<std::vector<int>> cells_;
  // A copy (~50 kB per frame), not a pointer: a Frame that is moved or copied after build()
  // must not leave its grid reading the keypoints of another object.
  std::vector<Vec2> uv_;
  bool built_ = false;
};

}  // namespace twistslam::tracking
