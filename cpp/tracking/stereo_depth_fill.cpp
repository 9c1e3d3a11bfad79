#include "tracking/stereo_depth_fill.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace twistslam::tracking {

std::vector<double> nearest_stereo_depths(const std::vector<Vec2>& stereo_uv,
                                          const std::vector<double>& stereo_depth,
                                          const std::vector<Vec2>& mono_uv,
                                          const StereoDepthFillOptions& options) {
  if (stereo_uv.size() != stereo_depth.size())
    throw std::invalid_argument("nearest_stereo_depths: stereo_uv and stereo_depth differ in size");
  std::vector<Vec2> uv;
  std::vector<double> depth;
  for (size_t i = 0; i < stereo_uv.size(); ++i)
    if (stereo_uv[i].allFinite() && std::isfinite(stereo_depth[i]) && stereo_depth[i] > 0)
      uv.push_back(stereo_uv[i]), depth.push_back(stereo_depth[i]);
  if (static_cast<int>(depth.size()) < std::max(1, options.min_stereo_points)) return {};
  const double share = static_cast<double>(depth.size()) / static_cast<double>(depth.size() + mono_uv.size());
  if (share < options.min_stereo_share) return {};
  std::vector<double> sorted = depth;
  const size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid), sorted.end());
  if (sorted[mid] > options.max_median_depth_m) return {};

  std::vector<double> out(mono_uv.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t m = 0; m < mono_uv.size(); ++m) {
    if (!mono_uv[m].allFinite()) continue;
    double best = std::numeric_limits<double>::infinity();
    for (size_t s = 0; s < uv.size(); ++s) {
      const double d2 = (uv[s] - mono_uv[m]).squaredNorm();
      if (d2 < best) best = d2, out[m] = depth[s];
    }
  }
  return out;
}

}  // namespace twistslam::tracking
